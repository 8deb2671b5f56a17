//! Everything grasp analysis says about an object resting on a table: antipodal grasps that
//! clear the table, their quality (nominal and robust Ferrari-Canny, Dex-Net 2.0's label) and
//! what physics makes of them. The library form of the `grasps` command.

use mvgrasp_geometry::Pose3;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::Result;
use crate::grasp::Grasp;
use crate::gripper::Gripper;
use crate::label::GraspLabel;
use crate::object::GraspObject;
use crate::physics::{
    PhysicsNoise, PhysicsObject, PhysicsOutcome, PhysicsParams, ShapeParams, SuccessEstimate,
    simulate_grasp, success_probability,
};
use crate::quality::{RobustQuality, RobustQualityParams, grasp_seed, robust_qualities};
use crate::sampling::{SamplingParams, SamplingReport, sample_antipodal};

/// What to compute, with every parameter.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct AnalysisConfig {
    /// Antipodal sampling (and its collision checks).
    pub sampling: SamplingParams,
    /// Robust Ferrari-Canny quality and the label threshold.
    pub quality: RobustQualityParams,
    /// Physics: run one trial per grasp when true.
    pub physics: Option<PhysicsParams>,
    /// Perturbed physics trials per grasp (0: none), under `physics_noise`.
    pub physics_trials: usize,
    /// Pose noise of the perturbed trials.
    pub physics_noise: PhysicsNoise,
    /// How physics shapes the object.
    pub shape: ShapeParams,
}

/// One grasp with everything known about it.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct AnalysedGrasp {
    /// The grasp in the world: the table frame (z up, the table the plane z = 0).
    pub grasp: Grasp,
    /// The grasp in the object's mesh frame.
    #[serde(with = "mvgrasp_geometry::pose_as_matrix")]
    pub object_from_gripper: Pose3,
    /// Robust quality (with the nominal epsilon and force closure inside).
    pub quality: RobustQuality,
    /// Dex-Net 2.0's label: robust epsilon above the threshold and collision-free (sampled
    /// grasps are collision-free by construction).
    pub robust_label: bool,
    /// The unperturbed physics trial, when physics ran.
    pub physics: Option<PhysicsOutcome>,
    /// The perturbed trials, when asked for.
    pub physics_success: Option<SuccessEstimate>,
}

/// Sampling's account and the analysed grasps, best robust epsilon first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Analysis {
    /// The object's placement on the table.
    #[serde(with = "mvgrasp_geometry::pose_as_matrix")]
    pub table_from_object: Pose3,
    /// What sampling tried and rejected (its grasps are those below, unsorted).
    pub sampling: SamplingReport,
    /// The grasps, by robust epsilon, best first.
    pub grasps: Vec<AnalysedGrasp>,
}

/// Samples, scores and (if configured) simulates grasps on `object` resting on the table at
/// `table_from_object`. Seeded: the same inputs and seed give the same analysis on any thread
/// count.
///
/// # Errors
/// Invalid parameters or gripper ([`crate::GraspError::InvalidParameter`]); an object physics
/// cannot prepare ([`crate::GraspError::Object`]).
pub fn analyse(
    object: &GraspObject,
    table_from_object: &Pose3,
    gripper: &Gripper,
    config: &AnalysisConfig,
    seed: u64,
) -> Result<Analysis> {
    config.quality.validate()?;
    let sampling = sample_antipodal(
        object,
        gripper,
        &config.sampling,
        Some(table_from_object),
        grasp_seed(seed, 0),
    )?;
    let poses: Vec<Pose3> = sampling
        .grasps
        .iter()
        .map(|g| g.grasp.world_from_gripper)
        .collect();
    let qualities = robust_qualities(
        object,
        &poses,
        gripper,
        &config.quality,
        grasp_seed(seed, 1),
    )?;
    let physics = config
        .physics
        .as_ref()
        .map(|params| {
            PhysicsObject::from_grasp_object(object, &config.shape).map(|body| (params, body))
        })
        .transpose()?;
    let physics_seed = grasp_seed(seed, 2);
    let mut grasps = sampling
        .grasps
        .par_iter()
        .zip(qualities.par_iter())
        .enumerate()
        .map(|(i, (sampled, quality))| {
            let grasp = Grasp {
                world_from_gripper: *table_from_object * sampled.grasp.world_from_gripper,
                width_m: sampled.grasp.width_m,
            };
            let (physics, physics_success) = match &physics {
                Some((params, body)) => {
                    let nominal = simulate_grasp(body, table_from_object, &grasp, gripper, params)?;
                    let perturbed = if config.physics_trials > 0 {
                        Some(success_probability(
                            body,
                            table_from_object,
                            &grasp,
                            gripper,
                            params,
                            &config.physics_noise,
                            config.physics_trials,
                            grasp_seed(physics_seed, i),
                        )?)
                    } else {
                        None
                    };
                    (Some(nominal), perturbed)
                }
                None => (None, None),
            };
            Ok(AnalysedGrasp {
                grasp,
                object_from_gripper: sampled.grasp.world_from_gripper,
                quality: *quality,
                // Sampling kept only approaches clear of the object and the table.
                robust_label: GraspLabel::of(*quality, true, &config.quality).robust,
                physics,
                physics_success,
            })
        })
        .collect::<Result<Vec<_>>>()?;
    grasps.sort_by(|a, b| {
        b.quality
            .robust_epsilon
            .total_cmp(&a.quality.robust_epsilon)
    });
    Ok(Analysis {
        table_from_object: *table_from_object,
        sampling,
        grasps,
    })
}
