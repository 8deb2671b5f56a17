//! What a round's cameras see: where they stand, the depth of colour views predicted by a
//! depth-from-RGB method, and the bin's workspace mask.

use mvgrasp_geometry::{Camera, Intrinsics, IntrinsicsPreset, Pose3, TriangleMesh, Vec3};
use mvgrasp_planner::DepthImage;
use mvgrasp_planner::Mask;
use mvgrasp_render::{Colors, Lighting, MeshInput, Renderer, random_colors};

use crate::convert::rgb_view_of;
use crate::depth_from_rgb::checked;
use crate::error::Result;
use crate::planner::DepthPredictor;
use crate::scene::{OBJECT_ID, SceneData, TABLE_HALF_SIDE_M, TABLE_ID, render_frames};

/// The rounds' cameras: the top-down one first, then `views - 1` around at 50 degrees, all
/// `distance` metres from the table's centre, each a `preset` camera.
///
/// # Errors
/// A distance at which a camera cannot look (not positive and finite).
pub fn cameras(views: usize, preset: IntrinsicsPreset, distance: f32) -> Result<Vec<Camera>> {
    let k = Intrinsics::preset(preset);
    let mut cameras = vec![Camera::look_at(
        k,
        Vec3::new(0.0, 0.0, distance),
        Vec3::ZERO,
        Vec3::Y,
    )?];
    let elevation = 50.0f32.to_radians();
    for i in 1..views {
        let azimuth = std::f32::consts::TAU * (i - 1) as f32 / (views - 1) as f32;
        let eye = Vec3::new(
            elevation.cos() * azimuth.cos(),
            elevation.cos() * azimuth.sin(),
            elevation.sin(),
        ) * distance;
        cameras.push(Camera::look_at(k, eye, Vec3::ZERO, Vec3::Z)?);
    }
    Ok(cameras)
}

/// How far inside the bin's walls its workspace mask ends, metres.
pub(super) const BIN_MARGIN_M: f32 = 0.01;

/// The bin's mask id in the colour views (after the scene's object and table ids).
const WALL_ID: u8 = TABLE_ID + 1;

/// The bin's colour: a plain blue tote.
const WALL_RGB: [u8; 3] = [70, 100, 150];

/// The pixels of `depth` that see something standing over the bin's floor (within `inside`
/// of its centre, 3 mm or more above it); `None` when there is none.
pub(super) fn bin_mask(camera: &Camera, depth: &DepthImage, inside: f32) -> Option<Mask> {
    let width = depth.width();
    let pixels = depth
        .as_slice()
        .iter()
        .enumerate()
        .map(|(i, &z)| {
            if !(z > 0.0 && z.is_finite()) {
                return false;
            }
            let (u, v) = ((i as u32 % width) as f32, (i as u32 / width) as f32);
            let p = camera.unproject(u, v, z);
            p.x.abs() < inside && p.y.abs() < inside && p.z > 0.003
        })
        .collect();
    Mask::new(width, depth.height(), pixels).ok()
}

/// Depth predicted by `method` from colour views of `objects` (random colours per
/// vertex seeded by `seed`) on the grey table, in `bin` (its walls' mesh) when there is
/// one. The method's masks are the foreground, objects and walls (what is not the table, as a
/// picker that knows its empty workspace tells apart), so that a wall hiding an object does
/// not carve it away; the walls' own pixels then take their known depth (the bin is a
/// fixture whose place the picker knows, as the table's), the objects' the method's.
pub(super) fn predicted_depths(
    renderer: &Renderer,
    method: &DepthPredictor,
    objects: &TriangleMesh,
    bin: Option<&TriangleMesh>,
    cameras: &[Camera],
    seed: u64,
) -> Result<Vec<DepthImage>> {
    let colours = random_colors(seed, objects.vertices().len());
    let data = SceneData::of_mesh(objects, &Pose3::IDENTITY, TABLE_HALF_SIDE_M);
    let mut inputs = data.mesh_inputs(objects.triangles(), Colors::PerVertex(&colours), true);
    let walls = bin.map(|bin| (bin, SceneData::of_mesh(bin, &Pose3::IDENTITY, 0.0)));
    if let Some((bin, data)) = &walls {
        let wall = data.mesh_inputs(bin.triangles(), Colors::Uniform(WALL_RGB), false);
        inputs.extend(wall.into_iter().map(|w| MeshInput {
            instance_id: WALL_ID,
            ..w
        }));
    }
    let frames = render_frames(renderer, &inputs, cameras, &Lighting::Headlight)?;
    // Each view in colour, its mask the objects' pixels and the walls'; the walls' pixels
    // and the rendered depth kept aside.
    let mut walls = Vec::with_capacity(frames.len());
    let mut views = Vec::with_capacity(frames.len());
    for (camera, frame) in cameras.iter().zip(frames) {
        let wall: Vec<bool> = frame.mask.iter().map(|&id| id == WALL_ID).collect();
        let (mut view, known) = rgb_view_of(camera, frame, OBJECT_ID);
        if let Some(mask) = view.mask.as_mut() {
            mask.iter_mut().zip(&wall).for_each(|(m, &w)| *m |= w);
        }
        walls.push((wall, known));
        views.push(view);
    }
    let predicted = checked(method, &views)?;
    let depths = cameras
        .iter()
        .zip(walls)
        .zip(predicted)
        .map(|((camera, (wall, known)), p)| {
            let depth = p
                .depth_m
                .iter()
                .zip(&wall)
                .zip(&known)
                .map(|((&predicted, &wall), &known)| if wall { known } else { predicted })
                .collect();
            DepthImage::new(camera.intrinsics, depth)
        })
        .collect::<mvgrasp_planner::Result<_>>()?;
    Ok(depths)
}
