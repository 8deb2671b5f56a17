//! An object at rest on a table, seen by simulated cameras: the scene's vertex data and mask
//! ids, and the one way it reaches the renderer ([`render_frames`]), for the planner's
//! rendered input (depth, colour and the photographic look, [`photoreal`]) and for the
//! dataset generators above it.

pub mod photoreal;

use mvgrasp_geometry::{Camera, Pose3, TriangleMesh};
use mvgrasp_planner::DepthImage;
use mvgrasp_render::{Colors, Frame, IDENTITY, Lighting, Material, MeshInput, Renderer, Sides};

use crate::convert::{render_view, sides_of};
use crate::error::Result;
use mvgrasp_geometry::pose_as_matrix::to_rows;

/// Mask value of the object.
pub const OBJECT_ID: u8 = 1;
/// Mask value of the table.
pub const TABLE_ID: u8 = 2;
/// The table's colour.
const TABLE_RGB: [u8; 3] = [150, 150, 150];
/// Half the side of the table square under the colour views (the RGB-D datasets' and the
/// planner's RGB input), metres.
pub const TABLE_HALF_SIDE_M: f32 = 0.4;
/// Half the side of the table square under the depth views ([`render_depths`]: the grasp
/// datasets' and the planner's rendered depth), metres: wide enough that no view at the
/// datasets' distances sees its edge.
pub const DEPTH_TABLE_HALF_SIDE_M: f32 = 1.5;

/// Owned vertex data for the renderer: an object's mesh in its pose, and a table square.
pub struct SceneData {
    positions: Vec<[f32; 3]>,
    world_from_object: [[f32; 4]; 4],
    table_positions: [[f32; 3]; 4],
    sides: Sides,
}

/// The table's two triangles.
const TABLE_TRIANGLES: [[u32; 3]; 2] = [[0, 1, 2], [0, 2, 3]];

impl SceneData {
    /// `mesh` at `table_from_object` and a table square `2 * table_half_side_m` wide at z = 0.
    pub fn of_mesh(mesh: &TriangleMesh, table_from_object: &Pose3, table_half_side_m: f32) -> Self {
        let h = table_half_side_m;
        Self {
            positions: mesh.vertices().iter().map(|v| v.to_array()).collect(),
            world_from_object: to_rows(table_from_object),
            sides: sides_of(mesh),
            table_positions: [[-h, -h, 0.0], [h, -h, 0.0], [h, h, 0.0], [-h, h, 0.0]],
        }
    }

    /// The meshes to upload: the object (`triangles` of the mesh this was made from) with
    /// `colors`, and the table if asked.
    pub fn mesh_inputs<'a>(
        &'a self,
        triangles: &'a [[u32; 3]],
        colors: Colors<'a>,
        table: bool,
    ) -> Vec<MeshInput<'a>> {
        let mut inputs = vec![MeshInput {
            positions: &self.positions,
            indices: triangles,
            sides: self.sides,
            colors,
            world_from_mesh: self.world_from_object,
            instance_id: OBJECT_ID,
            material: Material::MATTE,
        }];
        if table {
            inputs.push(MeshInput {
                positions: &self.table_positions,
                indices: &TABLE_TRIANGLES,
                sides: Sides::Both,
                colors: Colors::Uniform(TABLE_RGB),
                world_from_mesh: IDENTITY,
                instance_id: TABLE_ID,
                material: Material::MATTE,
            });
        }
        inputs
    }
}

/// Renders the meshes `inputs` from every camera under `lighting` (a frame per camera, in
/// order).
///
/// # Errors
/// A renderer error.
pub fn render_frames(
    renderer: &Renderer,
    inputs: &[MeshInput<'_>],
    cameras: &[Camera],
    lighting: &Lighting,
) -> Result<Vec<Frame>> {
    let scene = renderer.upload(inputs)?;
    let views: Vec<_> = cameras.iter().map(render_view).collect();
    Ok(renderer.render_lit(&scene, &views, lighting)?)
}

/// Depth images of `mesh` at `table_from_object` on a table ([`DEPTH_TABLE_HALF_SIDE_M`], its
/// top at z = 0), one per camera.
///
/// # Errors
/// A renderer error.
pub fn render_depths(
    renderer: &Renderer,
    mesh: &TriangleMesh,
    table_from_object: &Pose3,
    cameras: &[Camera],
) -> Result<Vec<DepthImage>> {
    let data = SceneData::of_mesh(mesh, table_from_object, DEPTH_TABLE_HALF_SIDE_M);
    let inputs = data.mesh_inputs(mesh.triangles(), Colors::Uniform([200, 200, 200]), true);
    let frames = render_frames(renderer, &inputs, cameras, &Lighting::Headlight)?;
    Ok(cameras
        .iter()
        .zip(frames)
        .map(|(camera, frame)| DepthImage::new(camera.intrinsics, frame.depth_m))
        .collect::<mvgrasp_planner::Result<_>>()?)
}
