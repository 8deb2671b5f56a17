//! The one way a grasp is labelled, for the grasp datasets, the planner's check of its choice,
//! the tests and the command-line tools: Dex-Net 2.0's label (robust Ferrari-Canny epsilon
//! above a threshold, and an approach that meets neither the object nor the table), with an
//! optional physics trial beside it.

use mvgrasp_geometry::Pose3;
use rayon::prelude::*;
use serde::Serialize;

use crate::collision::{CollisionParams, check_collision};
use crate::error::Result;
use crate::grasp::Grasp;
use crate::gripper::{Gripper, GripperPreset};
use crate::object::GraspObject;
use crate::physics::{PhysicsObject, PhysicsOutcome, PhysicsParams, ShapeParams, simulate_grasp};
use crate::quality::{RobustQuality, RobustQualityParams, robust_qualities};
use crate::sampling::SamplingParams;

/// What labels a grasp.
#[derive(Clone, Copy, Debug)]
pub struct LabelParams<'a> {
    /// Robust quality and the label's threshold.
    pub quality: &'a RobustQualityParams,
    /// The approach's collision check.
    pub collision: &'a CollisionParams,
    /// A rapier trial of each grasp, when given (with the object's physics body).
    pub physics: Option<(&'a PhysicsParams, &'a PhysicsObject)>,
}

/// Everything that decides how grasps on an object are found and judged: the gripper, the
/// antipodal sampler, the label and the rapier trial. The default is the shipped grasp
/// datasets' (the Panda hand; 2,000 sampling tries; Dex-Net 2.0's robust quality), so that a
/// planner checking its choice with it measures what its networks were trained to predict.
#[derive(Clone, Debug, PartialEq)]
pub struct LabelSettings {
    /// The gripper.
    pub gripper: Gripper,
    /// Antipodal sampling (friction cone, tries, duplicates, collision margins).
    pub sampling: SamplingParams,
    /// Robust quality (Dex-Net 2.0's perturbations and label threshold).
    pub quality: RobustQualityParams,
    /// The physics trial.
    pub physics: PhysicsParams,
    /// How the physics trial shapes the object.
    pub physics_shape: ShapeParams,
}

impl Default for LabelSettings {
    fn default() -> Self {
        Self {
            gripper: Gripper::preset(GripperPreset::Panda),
            sampling: SamplingParams {
                max_tries: 2000,
                ..SamplingParams::default()
            },
            quality: RobustQualityParams::default(),
            physics: PhysicsParams::default(),
            physics_shape: ShapeParams::default(),
        }
    }
}

impl LabelSettings {
    /// How these settings label grasps ([`label_grasps`]), with a rapier trial on `body` when
    /// given.
    pub fn label_params<'a>(&'a self, body: Option<&'a PhysicsObject>) -> LabelParams<'a> {
        LabelParams {
            quality: &self.quality,
            collision: &self.sampling.collision,
            physics: body.map(|body| (&self.physics, body)),
        }
    }
}

/// A grasp's label and what it rests on.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct GraspLabel {
    /// Robust Ferrari-Canny quality.
    pub quality: RobustQuality,
    /// Whether the open hand reaches the grasp along its approach without touching the object
    /// or the table.
    pub collision_free: bool,
    /// Dex-Net 2.0's label: collision-free and robust epsilon above the threshold.
    pub robust: bool,
    /// The rapier trial (close, lift, shake), when asked for.
    pub physics: Option<PhysicsOutcome>,
}

impl GraspLabel {
    /// The label of a grasp whose robust quality and collision check are known (the grasp
    /// datasets score each antipodal axis once and check each view's approach apart).
    pub fn of(quality: RobustQuality, collision_free: bool, params: &RobustQualityParams) -> Self {
        Self {
            quality,
            collision_free,
            robust: params.dexnet_label(quality.robust_epsilon, collision_free),
            physics: None,
        }
    }
}

/// Labels each of `grasps` (in the table frame, with their widths) on `object` resting at
/// `table_from_object`; robust quality seeded from `seed` as [`robust_qualities`] seeds it.
/// Parallel, and the same on any thread count.
///
/// # Errors
/// Invalid quality, gripper or physics parameters.
pub fn label_grasps(
    object: &GraspObject,
    table_from_object: &Pose3,
    grasps: &[Grasp],
    gripper: &Gripper,
    params: &LabelParams<'_>,
    seed: u64,
) -> Result<Vec<GraspLabel>> {
    let object_from_table = table_from_object.inverse();
    let object_from_grippers: Vec<Pose3> = grasps
        .iter()
        .map(|g| object_from_table * g.world_from_gripper)
        .collect();
    let qualities = robust_qualities(object, &object_from_grippers, gripper, params.quality, seed)?;
    grasps
        .par_iter()
        .zip(object_from_grippers.par_iter())
        .zip(qualities)
        .map(|((grasp, object_from_gripper), quality)| {
            let collision_free = check_collision(
                object,
                gripper,
                object_from_gripper,
                grasp.width_m,
                Some(table_from_object),
                params.collision,
            )
            .is_free();
            let mut label = GraspLabel::of(quality, collision_free, params.quality);
            if let Some((physics, body)) = params.physics {
                label.physics = Some(simulate_grasp(
                    body,
                    table_from_object,
                    grasp,
                    gripper,
                    physics,
                )?);
            }
            Ok(label)
        })
        .collect()
}
