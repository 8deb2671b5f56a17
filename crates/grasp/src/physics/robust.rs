//! Robust physics success: the fraction of trials that hold under pose noise
//! ([`success_probability`]).

use mvgrasp_geometry::{Pose3, Rot3, Vec3};
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

use crate::error::{GraspError, Result};
use crate::grasp::Grasp;
use crate::gripper::Gripper;
use crate::physics::object::PhysicsObject;
use crate::physics::params::{PhysicsNoise, PhysicsParams};
use crate::physics::trial::{FailureStage, simulate_grasp_among};

/// The result of [`success_probability`].
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct SuccessEstimate {
    /// Successes over trials.
    pub probability: f64,
    /// Trials run.
    pub trials: usize,
    /// Trials that held the object to the end.
    pub successes: usize,
    /// Failed trials by stage.
    pub failures: StageCounts,
}

impl SuccessEstimate {
    /// The share of the trials whose object stayed in its pose until the gripper came (no
    /// [`FailureStage::Settle`]) that held: what the grasp is worth, apart from a resting pose
    /// the trial's shape does not keep. `None` when no trial got that far.
    pub fn settled_rate(&self) -> Option<f64> {
        let settled = self.trials - self.failures.settle;
        (settled > 0).then(|| self.successes as f64 / settled as f64)
    }
}

/// Failed trials counted by [`FailureStage`].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct StageCounts {
    /// [`FailureStage::Settle`].
    pub settle: usize,
    /// [`FailureStage::Approach`].
    pub approach: usize,
    /// [`FailureStage::Close`].
    pub close: usize,
    /// [`FailureStage::Lift`].
    pub lift: usize,
    /// [`FailureStage::Shake`].
    pub shake: usize,
}

impl StageCounts {
    /// The failures at `stage`.
    pub fn of(&self, stage: FailureStage) -> usize {
        match stage {
            FailureStage::Settle => self.settle,
            FailureStage::Approach => self.approach,
            FailureStage::Close => self.close,
            FailureStage::Lift => self.lift,
            FailureStage::Shake => self.shake,
        }
    }

    /// The stage most failures happened at (the earliest of a tie); `None` without failures.
    pub fn most_common(&self) -> Option<FailureStage> {
        // `max_by_key` keeps the last of equal maxima: walk the stages backwards.
        FailureStage::ALL
            .into_iter()
            .rev()
            .filter(|&stage| self.of(stage) > 0)
            .max_by_key(|&stage| self.of(stage))
    }

    /// Counts one failure at `stage`.
    pub fn count(&mut self, stage: FailureStage) {
        let slot = match stage {
            FailureStage::Settle => &mut self.settle,
            FailureStage::Approach => &mut self.approach,
            FailureStage::Close => &mut self.close,
            FailureStage::Lift => &mut self.lift,
            FailureStage::Shake => &mut self.shake,
        };
        *slot += 1;
    }
}

impl std::ops::AddAssign for StageCounts {
    fn add_assign(&mut self, other: Self) {
        self.settle += other.settle;
        self.approach += other.approach;
        self.close += other.close;
        self.lift += other.lift;
        self.shake += other.shake;
    }
}

/// Runs `n_trials` of [`simulate_grasp`], each with the gripper and the object's placement
/// perturbed by `noise` (and the pads' friction drawn about the gripper's), and returns the
/// fraction that succeed.
///
/// Trial `i` draws its noise from ChaCha8 seeded with `seed` on stream `i`, so the estimate is
/// the same for any thread count (trials run in parallel on rayon's pool). The gripper's
/// perturbation is a translation and a rotation vector in its own frame, about the grasp
/// centre; the object's is a translation in the table plane and a turn about the vertical
/// through its centre of mass.
///
/// # Errors
/// [`GraspError::InvalidParameter`] for `n_trials` = 0, invalid noise, or anything
/// [`simulate_grasp`] rejects.
#[allow(clippy::too_many_arguments)] // object, placement, grasp, hand, physics, noise, count, seed
pub fn success_probability(
    object: &PhysicsObject,
    table_from_object: &Pose3,
    grasp: &Grasp,
    gripper: &Gripper,
    params: &PhysicsParams,
    noise: &PhysicsNoise,
    n_trials: usize,
    seed: u64,
) -> Result<SuccessEstimate> {
    success_probability_among(
        object,
        table_from_object,
        &[],
        grasp,
        gripper,
        params,
        noise,
        n_trials,
        seed,
    )
}

/// [`success_probability`] with other objects on the table (`neighbours`, each resting at its
/// pose, unperturbed): each trial is [`crate::physics::simulate_grasp_among`]'s, so the object
/// must come out alone. Without neighbours it is [`success_probability`], trial for trial.
///
/// # Errors
/// See [`success_probability`]; a non-finite neighbour pose.
#[allow(clippy::too_many_arguments)]
pub fn success_probability_among(
    object: &PhysicsObject,
    table_from_object: &Pose3,
    neighbours: &[(&PhysicsObject, Pose3)],
    grasp: &Grasp,
    gripper: &Gripper,
    params: &PhysicsParams,
    noise: &PhysicsNoise,
    n_trials: usize,
    seed: u64,
) -> Result<SuccessEstimate> {
    if n_trials == 0 {
        return Err(GraspError::InvalidParameter {
            op: "physics success probability",
            name: "n_trials",
            value: "0".into(),
            expected: "at least 1",
        });
    }
    noise.validate()?;
    params.validate()?;
    gripper.validate()?;
    let com = table_from_object.transform_point(object.center_of_mass());
    let outcomes: Vec<_> = (0..n_trials)
        .into_par_iter()
        .map(|i| {
            let mut rng = ChaCha8Rng::seed_from_u64(seed);
            rng.set_stream(i as u64);
            let (placed, perturbed, friction) = perturb(
                noise,
                table_from_object,
                com,
                grasp,
                gripper.pad_friction,
                &mut rng,
            );
            let hand = Gripper {
                pad_friction: friction,
                ..gripper.clone()
            };
            simulate_grasp_among(object, &placed, neighbours, &perturbed, &hand, params)
        })
        .collect();
    let mut estimate = SuccessEstimate {
        probability: 0.0,
        trials: n_trials,
        successes: 0,
        failures: StageCounts::default(),
    };
    for outcome in outcomes {
        match outcome?.failed_at {
            None => estimate.successes += 1,
            Some(stage) => estimate.failures.count(stage),
        }
    }
    estimate.probability = estimate.successes as f64 / n_trials as f64;
    Ok(estimate)
}

/// One trial's object placement, grasp and pad friction under `noise`.
fn perturb(
    noise: &PhysicsNoise,
    table_from_object: &Pose3,
    com: Vec3,
    grasp: &Grasp,
    friction: f32,
    rng: &mut ChaCha8Rng,
) -> (Pose3, Grasp, f32) {
    let mut normal = || -> f32 { StandardNormal.sample(rng) };
    let shift = Vec3::new(normal(), normal(), 0.0) * noise.object_translation_sigma_m;
    let yaw = normal() * noise.object_yaw_sigma_rad;
    let gripper_shift = Vec3::new(normal(), normal(), normal()) * noise.gripper_translation_sigma_m;
    let gripper_turn = Vec3::new(normal(), normal(), normal()) * noise.gripper_rotation_sigma_rad;
    let friction = (friction + normal() * noise.friction_sigma).max(noise.friction_min);

    // Turn about the vertical through the centre of mass, then shift in the table plane.
    let table_motion = Pose3::from_translation(com + shift)
        * Pose3::from_rotation(Rot3::from_rotation_z(yaw))
        * Pose3::from_translation(-com);
    let gripper_motion = Pose3::from_parts(gripper_shift, Rot3::from_scaled_axis(gripper_turn));
    let perturbed = Grasp {
        world_from_gripper: grasp.world_from_gripper * gripper_motion,
        width_m: grasp.width_m,
    };
    (table_motion * *table_from_object, perturbed, friction)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_most_common_failure_is_the_earliest_of_a_tie() {
        assert_eq!(StageCounts::default().most_common(), None);
        let counts = StageCounts {
            approach: 2,
            lift: 2,
            shake: 1,
            ..StageCounts::default()
        };
        assert_eq!(counts.most_common(), Some(FailureStage::Approach));
        let counts = StageCounts { shake: 3, ..counts };
        assert_eq!(counts.most_common(), Some(FailureStage::Shake));
    }

    #[test]
    fn the_settled_rate_leaves_out_trials_that_lost_the_pose() {
        let estimate = SuccessEstimate {
            probability: 0.3,
            trials: 10,
            successes: 3,
            failures: StageCounts {
                settle: 4,
                approach: 3,
                ..StageCounts::default()
            },
        };
        assert_eq!(estimate.settled_rate(), Some(0.5));
        let lost = SuccessEstimate {
            probability: 0.0,
            trials: 2,
            successes: 0,
            failures: StageCounts {
                settle: 2,
                ..StageCounts::default()
            },
        };
        assert_eq!(lost.settled_rate(), None);
    }
}
