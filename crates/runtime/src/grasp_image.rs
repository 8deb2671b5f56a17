//! A picture of grasps on an object: the object on its table and, for each grasp, a sketch of
//! the hand in a colour of its own (the two fingers at the grasp's width, the bar joining them
//! and a stem along the approach), seen from above at an angle.

use std::path::Path;

use mvgrasp_geometry::{Camera, Intrinsics, Pose3, Rot3, TriangleMesh, Vec3};
use mvgrasp_grasp::{Grasp, Gripper};
use mvgrasp_render::{Backend, Colors, IDENTITY, Material, MeshInput, Renderer, Sides};
use parry3d::shape::Cuboid;

use crate::convert::{render_view, sides_of};
use crate::error::Result;
use crate::images::write_png8;
use mvgrasp_geometry::pose_as_matrix::to_rows;

/// Colours of the grasps, best first: green, blue, orange, purple, cyan, then grey.
pub const GRASP_COLORS: [[u8; 3]; 5] = [
    [40, 200, 60],
    [40, 110, 230],
    [240, 150, 30],
    [170, 60, 200],
    [30, 200, 210],
];

/// A box's world-frame vertices, triangles and colour.
type ColoredBox = (Vec<[f32; 3]>, Vec<[u32; 3]>, [u8; 3]);

const OBJECT_RGB: [u8; 3] = [200, 190, 170];
const TABLE_RGB: [u8; 3] = [110, 110, 120];

/// Renders `mesh` placed by `table_from_object` with the hands of `grasps` (world frame), each
/// opened to its width, into a 640 x 480 PNG at `path`.
///
/// # Errors
/// No graphics adapter or a render failure ([`crate::Error::Render`]); the PNG cannot be
/// written ([`crate::Error::Io`]).
pub fn write_grasp_picture(
    path: &Path,
    mesh: &TriangleMesh,
    table_from_object: &Pose3,
    grasps: &[Grasp],
    gripper: &Gripper,
) -> Result<()> {
    let colored: Vec<(Grasp, [u8; 3])> = grasps
        .iter()
        .enumerate()
        .map(|(i, g)| (*g, GRASP_COLORS.get(i).copied().unwrap_or([150, 150, 150])))
        .collect();
    write_colored_grasp_picture(path, mesh, table_from_object, &colored, gripper)
}

/// [`write_grasp_picture`] with each hand in its own colour.
///
/// # Errors
/// See [`write_grasp_picture`].
pub fn write_colored_grasp_picture(
    path: &Path,
    mesh: &TriangleMesh,
    table_from_object: &Pose3,
    grasps: &[(Grasp, [u8; 3])],
    gripper: &Gripper,
) -> Result<()> {
    let boxes: Vec<ColoredBox> = grasps
        .iter()
        .flat_map(|&(grasp, color)| {
            hand_sketch(gripper, grasp.width_m)
                .into_iter()
                .map(move |(half, gripper_from_box)| {
                    let (vertices, triangles) = Cuboid::new(half).to_trimesh();
                    let world_from_box = grasp.world_from_gripper * gripper_from_box;
                    let positions = vertices
                        .iter()
                        .map(|v| world_from_box.transform_point(*v).to_array())
                        .collect();
                    (positions, triangles, color)
                })
        })
        .collect();
    let object_positions: Vec<[f32; 3]> = mesh.vertices().iter().map(|v| v.to_array()).collect();
    let extent = mesh.aabb().extents().max_element();
    let h = 0.15 + extent;
    let table_positions = [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]];
    let table_triangles = [[0, 1, 2], [0, 2, 3]];
    let mut inputs = vec![
        MeshInput {
            positions: &object_positions,
            indices: mesh.triangles(),
            sides: sides_of(mesh),
            colors: Colors::Uniform(OBJECT_RGB),
            world_from_mesh: to_rows(table_from_object),
            instance_id: 1,
            material: Material::MATTE,
        },
        MeshInput {
            positions: &table_positions,
            indices: &table_triangles,
            sides: Sides::Both,
            colors: Colors::Uniform(TABLE_RGB),
            world_from_mesh: IDENTITY,
            instance_id: 2,
            material: Material::MATTE,
        },
    ];
    for (positions, triangles, color) in &boxes {
        inputs.push(MeshInput {
            positions,
            indices: triangles,
            sides: Sides::Front,
            colors: Colors::Uniform(*color),
            world_from_mesh: IDENTITY,
            instance_id: 3,
            material: Material::MATTE,
        });
    }
    let renderer = Renderer::new(Backend::Auto)?;
    let scene = renderer.upload(&inputs)?;
    let center = table_from_object.transform_point(mesh.aabb().center());
    let distance = 0.12 + 2.5 * extent;
    let eye = center + Vec3::new(0.55, -0.45, 0.7).normalize() * distance;
    let intrinsics = Intrinsics::new(600.0, 600.0, 319.5, 239.5, 640, 480, 0.05, 5.0)?;
    let camera = Camera::look_at(intrinsics, eye, center, Vec3::Z)?;
    let frame = renderer.render_one(&scene, &render_view(&camera))?;
    write_png8(path, frame.width, frame.height, 3, &frame.rgb)
}

/// The sketch's boxes (half extents, pose in the gripper frame): fingers `width_m` apart, the
/// bar behind them, a stem along -z.
fn hand_sketch(gripper: &Gripper, width_m: f32) -> [(Vec3, Pose3); 4] {
    let t = gripper.finger_thickness_m;
    let len = gripper.finger_length_m;
    let w = gripper.finger_width_m;
    let at = |x: f32, z: f32| Pose3::from_parts(Vec3::new(x, 0.0, z), Rot3::IDENTITY);
    let finger = Vec3::new(t / 2.0, w / 2.0, len / 2.0);
    let x = (width_m + t) / 2.0;
    [
        (finger, at(-x, -len / 2.0)),
        (finger, at(x, -len / 2.0)),
        (
            Vec3::new(x + t / 2.0, t / 2.0, t / 2.0),
            at(0.0, -len - t / 2.0),
        ),
        (Vec3::new(t / 2.0, t / 2.0, 0.02), at(0.0, -len - t - 0.02)),
    ]
}
