//! The datapoints of one object: its stable poses, antipodal axes scored once per pose, cameras
//! that render its depth, and the grasps that approach along each view.

use mvgrasp_geometry::{Pose3, RestingPoses, TriangleMesh, Vec3};
use mvgrasp_grasp::physics::{PhysicsNoise, PhysicsObject, success_probability_among};
use mvgrasp_grasp::quality::{grasp_seed, robust_qualities};
use mvgrasp_grasp::{
    AntipodalAxis, Grasp, GraspLabel, GraspObject, Gripper, canonical_frame, check_collision,
    sample_antipodal_axes,
};
use mvgrasp_render::Renderer;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use std::sync::Arc;

use mvgrasp_planner::{crop_depth, theta_rad};

use super::cameras::sample_camera;
use super::clutter::{Neighbour, hits_a_neighbour, place, scene_mesh};
use super::config::GraspDatasetConfig;
use super::noise::add_depth_noise;
use super::shard::Datapoint;
use crate::dataset::splitmix;
use crate::error::Result;
use crate::scene::render_depths;
use mvgrasp_geometry::pose_as_matrix::to_rows;

/// What the generator resolved from the config once.
pub(crate) struct Resolved {
    pub gripper: Gripper,
    pub intrinsics: mvgrasp_geometry::Intrinsics,
}

/// The seeds of one object, all derived from its seed.
fn seed_of(object_seed: u64, what: u64, a: u64, b: u64) -> u64 {
    splitmix(splitmix(splitmix(object_seed ^ what) ^ a) ^ b)
}

const SAMPLING: u64 = 1;
const QUALITY: u64 = 2;
const CAMERA: u64 = 3;
const NOISE: u64 = 4;
const PHYSICS: u64 = 5;
const PHYSICS_NOISE: u64 = 6;
const CLUTTER: u64 = 7;

/// The seed of the robust quality of axis `grasp` in pose `pose` (what `quality_seed` records).
pub(crate) fn quality_seed(object_seed: u64, pose: usize, grasp: usize) -> u64 {
    grasp_seed(seed_of(object_seed, QUALITY, pose as u64, 0), grasp)
}

/// All datapoints of `mesh` (object `object_id`, seeded with `object_seed`), in the order
/// stable pose, view, axis, with `neighbours` packed around it in each pose when the config
/// has clutter. An object with no stable pose or no antipodal axis gives none.
pub(crate) fn object_datapoints(
    renderer: &Renderer,
    mesh: &TriangleMesh,
    object_id: u32,
    object_seed: u64,
    config: &GraspDatasetConfig,
    resolved: &Resolved,
    neighbours: &[Arc<Neighbour>],
) -> Result<Vec<Datapoint>> {
    let poses: Vec<_> = RestingPoses::of(mesh)?
        .iter()
        .take(config.stable_poses_per_object)
        .map(|(_, pose)| *pose)
        .collect();
    let object = GraspObject::new(mesh.clone())?;
    let physics_object = if config.physics_fraction > 0.0 {
        Some(PhysicsObject::from_grasp_object(
            &object,
            &config.physics_shape,
        )?)
    } else {
        None
    };
    let com = object.center_of_mass();
    let mut points = Vec::new();
    for (pose_index, pose) in poses.iter().enumerate() {
        let table_from_object = pose.table_from_object;
        let axes = sample_antipodal_axes(
            &object,
            &resolved.gripper,
            &config.sampling,
            config.grasps_per_pose,
            seed_of(object_seed, SAMPLING, pose_index as u64, 0),
        )?;
        if axes.is_empty() {
            continue;
        }
        let frames: Vec<Pose3> = axes.iter().map(|a| a.object_from_gripper(0.0)).collect();
        let qualities = robust_qualities(
            &object,
            &frames,
            &resolved.gripper,
            &config.quality,
            seed_of(object_seed, QUALITY, pose_index as u64, 0),
        )?;
        let target = table_from_object.transform_point(com);
        let cameras = (0..config.views_per_pose)
            .map(|view| {
                let mut rng = ChaCha8Rng::seed_from_u64(seed_of(
                    object_seed,
                    CAMERA,
                    pose_index as u64,
                    view as u64,
                ));
                sample_camera(&config.cameras, resolved.intrinsics, target, &mut rng)
            })
            .collect::<Result<Vec<_>>>()?;
        let placed = match &config.clutter {
            Some(params) => {
                let seed = seed_of(object_seed, CLUTTER, pose_index as u64, 0);
                place(
                    mesh,
                    &table_from_object,
                    neighbours,
                    params,
                    &mut ChaCha8Rng::seed_from_u64(seed),
                )
            }
            None => Vec::new(),
        };
        let frames_rendered = if placed.is_empty() {
            render_depths(renderer, mesh, &table_from_object, &cameras)?
        } else {
            let scene = scene_mesh(mesh, &table_from_object, neighbours, &placed)?;
            render_depths(renderer, &scene, &Pose3::IDENTITY, &cameras)?
        };
        let mut candidates = Vec::new();
        for (view, (camera, mut depth)) in cameras.iter().zip(frames_rendered).enumerate() {
            let (w, h) = (camera.intrinsics.width, camera.intrinsics.height);
            if config.noise.enabled {
                let seed = seed_of(object_seed, NOISE, pose_index as u64, view as u64);
                add_depth_noise(&mut depth, &config.noise, seed);
            }
            let optical = camera.optical_axis();
            let max_tilt = config.max_tilt_deg.to_radians();
            for (grasp_index, (axis, quality)) in axes.iter().zip(&qualities).enumerate() {
                let Some(object_from_gripper) =
                    aligned_frame(axis, &table_from_object, optical, max_tilt)
                else {
                    continue;
                };
                let grasp = Grasp {
                    world_from_gripper: table_from_object * object_from_gripper,
                    width_m: axis.contacts.width_m,
                };
                // A little slack: the frame was built within the tilt limit.
                let Some(image) = grasp.to_image(camera, max_tilt + 1e-4) else {
                    continue;
                };
                let [u, v] = image.center_px;
                if !(0.0..w as f32).contains(&u) || !(0.0..h as f32).contains(&v) {
                    continue;
                }
                let collision = check_collision(
                    &object,
                    &resolved.gripper,
                    &object_from_gripper,
                    grasp.width_m,
                    Some(&table_from_object),
                    &config.sampling.collision,
                );
                // The one label ([`GraspLabel`]): the axis's robust quality, scored once for
                // every view, and this view's approach.
                let free = collision.is_free()
                    && !hits_a_neighbour(
                        &resolved.gripper,
                        &grasp.world_from_gripper,
                        grasp.width_m,
                        neighbours,
                        &placed,
                    );
                let label = GraspLabel::of(*quality, free, &config.quality);
                candidates.push(Datapoint {
                    crop: crop_depth(&depth, image.center_px, image.angle_rad, &config.crop),
                    grasp_depth_m: image.depth_m,
                    theta_rad: theta_rad(camera),
                    angle_rad: image.angle_rad,
                    center_px: image.center_px,
                    width_m: axis.contacts.width_m,
                    robust_epsilon: quality.robust_epsilon as f32,
                    robust_label: label.robust,
                    collision_free: label.collision_free,
                    force_closure: quality.nominal_force_closure,
                    physics: -1,
                    physics_rate: -1.0,
                    physics_stage: -1,
                    object_id,
                    stable_pose: pose_index as u32,
                    view: view as u32,
                    grasp: grasp_index as u32,
                    quality_seed: quality_seed(object_seed, pose_index, grasp_index),
                    object_from_gripper: to_rows(&object_from_gripper),
                    table_from_object: to_rows(&table_from_object),
                    world_from_camera: to_rows(&camera.world_from_camera),
                });
            }
        }
        if let Some(physics_object) = &physics_object {
            // The trial among the neighbours placed for this pose, where they rest.
            let around: Vec<(&PhysicsObject, Pose3)> = placed
                .iter()
                .map(|p| {
                    let shapes = neighbours[p.index].physics(&config.physics_shape)?;
                    Ok((shapes, p.table_from_neighbour))
                })
                .collect::<Result<_>>()?;
            run_physics(
                &mut candidates,
                (physics_object, &around),
                &table_from_object,
                object_seed,
                config,
                resolved,
            )?;
        }
        points.extend(candidates);
    }
    Ok(points)
}

/// The gripper frame (object frame) on `axis` whose approach is the camera's optical axis
/// turned to lie across the grasp axis, if that turn is at most `max_tilt_rad`.
fn aligned_frame(
    axis: &AntipodalAxis,
    table_from_object: &Pose3,
    optical_world: Vec3,
    max_tilt_rad: f32,
) -> Option<Pose3> {
    let optical = table_from_object.inverse_transform_vector(optical_world);
    let x = axis.axis();
    let along = optical.dot(x);
    if along.abs() > max_tilt_rad.sin() {
        return None;
    }
    let z = (optical - x * along).normalize_or_zero();
    if z == Vec3::ZERO {
        return None;
    }
    // canonical_frame(angle) approaches along z0 cos(angle) + y0 sin(angle), where z0 and y0
    // are its approach and y at angle 0.
    let canonical = canonical_frame(axis.center, x, 0.0);
    let z0 = canonical.transform_vector(Vec3::Z);
    let y0 = canonical.transform_vector(Vec3::Y);
    Some(canonical_frame(axis.center, x, z.dot(y0).atan2(z.dot(z0))))
}

/// Runs a rapier trial for the chosen share of the collision-free datapoints (in parallel,
/// each trial deterministic).
fn run_physics(
    points: &mut [Datapoint],
    (physics_object, neighbours): (&PhysicsObject, &[(&PhysicsObject, Pose3)]),
    table_from_object: &Pose3,
    object_seed: u64,
    config: &GraspDatasetConfig,
    resolved: &Resolved,
) -> Result<()> {
    // A datapoint's seed for `what`, from its ids.
    let seed = |what: u64, p: &Datapoint| {
        seed_of(
            object_seed,
            what,
            u64::from(p.stable_pose) << 32 | u64::from(p.view),
            u64::from(p.grasp),
        )
    };
    let threshold = (config.physics_fraction as f64 * u64::MAX as f64) as u64;
    let chosen: Vec<usize> = points
        .iter()
        .enumerate()
        .filter(|(_, p)| p.collision_free && seed(PHYSICS, p) <= threshold)
        .map(|(i, _)| i)
        .collect();
    let noise = PhysicsNoise::matching(&config.quality);
    let estimates = chosen
        .par_iter()
        .map(|&i| {
            let p = &points[i];
            // The rows were written from a rigid pose a few lines above.
            let object_from_gripper = mvgrasp_geometry::pose_as_matrix::from_rows(
                p.object_from_gripper,
            )
            .map_err(|_| mvgrasp_grasp::GraspError::InvalidParameter {
                op: "physics labels",
                name: "object_from_gripper",
                value: format!("{:?}", p.object_from_gripper),
                expected: "a rigid transform",
            })?;
            let grasp = Grasp {
                world_from_gripper: *table_from_object * object_from_gripper,
                width_m: p.width_m,
            };
            success_probability_among(
                physics_object,
                table_from_object,
                neighbours,
                &grasp,
                &resolved.gripper,
                &config.physics,
                &noise,
                config.physics_trials,
                seed(PHYSICS_NOISE, p),
            )
        })
        .collect::<std::result::Result<Vec<_>, _>>()?;
    for (&i, estimate) in chosen.iter().zip(estimates) {
        // Trials whose object left its resting pose before the gripper came judge the shape,
        // not the grasp (see `SuccessEstimate::settled_rate`).
        let rate = estimate.settled_rate();
        points[i].physics_rate = rate.map_or(-1.0, |r| r as f32);
        points[i].physics = rate.map_or(-1, |r| i8::from(r >= 0.5));
        points[i].physics_stage = estimate.failures.most_common().map_or(-1, |s| s as i8);
    }
    Ok(())
}
