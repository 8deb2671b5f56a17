//! The labels suite: the grasp labels the networks learn, against the physics outcome they are
//! meant to predict.
//!
//! Each object rests in its most probable pose (an object whose every pose is marginal, one
//! that only rolls, is left out: grasps are judged on objects that rest); antipodal grasps are
//! sampled on it and labelled three ways: Dex-Net 2.0's robust Ferrari-Canny label, the
//! physics label (at least half of K perturbed trials hold: the grasp datasets' label) and both
//! together. Each is compared with an outcome drawn independently (K' more perturbed trials,
//! other seeds, the same perturbations): held when at least half of them hold. Trials whose
//! object left its resting pose before the hand came (the trial's shape does not keep the pose)
//! are left out of both rates, and a grasp none of whose trials got that far is not judged.

use mvgrasp_geometry::{Pose3, RestingPoses, TriangleMesh};
use mvgrasp_grasp::physics::{
    PhysicsNoise, PhysicsObject, PhysicsParams, StageCounts, SuccessEstimate, success_probability,
};
use mvgrasp_grasp::quality::{RobustQualityParams, grasp_seed};
use mvgrasp_grasp::{AnalysisConfig, Grasp, GraspObject, Gripper, SamplingParams, analyse};
use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// The suite's sizes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct LabelSuite {
    /// Grasps sampled per object.
    pub grasps: usize,
    /// Perturbed trials of the physics label.
    pub trials: usize,
    /// Perturbed trials of the outcome.
    pub outcome_trials: usize,
}

/// One grasp's labels and outcome.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct LabelRecord {
    /// The object's set.
    pub set: String,
    /// The object's name in its set.
    pub object: String,
    /// Its category or source.
    pub group: String,
    /// The robust Ferrari-Canny quality.
    pub robust_epsilon: f64,
    /// Dex-Net 2.0's robust label.
    pub robust: bool,
    /// Of the label's trials that got past settling, the share that held.
    pub physics_rate: Option<f64>,
    /// The same of the outcome's trials.
    pub outcome_rate: Option<f64>,
    /// The outcome's failed trials by stage.
    pub outcome_failures: StageCounts,
}

impl LabelRecord {
    /// The labels (robust, physics, both) and the outcome; `None` when either rate is
    /// missing (no trial got past settling).
    pub fn judged(&self) -> Option<([bool; 3], bool)> {
        let physics = self.physics_rate? >= 0.5;
        let held = self.outcome_rate? >= 0.5;
        Some(([self.robust, physics, self.robust && physics], held))
    }
}

impl LabelSuite {
    /// The grasp analysis that samples and labels: `grasps` antipodal grasps, the robust
    /// quality's defaults, and `trials` perturbed trials with the perturbations that match it.
    pub fn analysis_config(&self) -> AnalysisConfig {
        let quality = RobustQualityParams::default();
        let physics_noise = PhysicsNoise::matching(&quality);
        AnalysisConfig {
            sampling: SamplingParams {
                target_grasps: self.grasps,
                max_tries: 100 * self.grasps,
                ..Default::default()
            },
            quality,
            physics: Some(PhysicsParams::default()),
            physics_trials: self.trials,
            physics_noise,
            ..AnalysisConfig::default()
        }
    }

    /// The outcome of grasp `index` (of an analysis seeded by `seed`) on `body` at
    /// `table_from_object`: `outcome_trials` perturbed trials seeded apart from the label's
    /// (`analyse` seeds those from `grasp_seed(seed, 2)`).
    ///
    /// # Errors
    /// A trial that cannot run.
    pub fn outcome(
        &self,
        (body, table_from_object): (&PhysicsObject, &Pose3),
        (grasp, index): (&Grasp, usize),
        seed: u64,
    ) -> Result<SuccessEstimate> {
        let config = self.analysis_config();
        Ok(success_probability(
            body,
            table_from_object,
            grasp,
            &Gripper::default(),
            &config.physics.unwrap_or_default(),
            &config.physics_noise,
            self.outcome_trials,
            grasp_seed(grasp_seed(seed, 3), index),
        )?)
    }

    /// The labels of `mesh` (of `set`, named `object`, in `group`) with the sampling, quality
    /// and trials seeded by `seed`; empty for an object that only rolls.
    ///
    /// # Errors
    /// A mesh the grasp analysis refuses, or a trial that cannot run.
    pub fn run(
        &self,
        (set, object, group): (&str, &str, &str),
        mesh: TriangleMesh,
        seed: u64,
    ) -> Result<Vec<LabelRecord>> {
        let config = self.analysis_config();
        let gripper = Gripper::default();
        let rest = RestingPoses::of(&mesh)?;
        if rest.only_marginal() {
            return Ok(Vec::new());
        }
        let (_, pose) = rest.get(0)?;
        let table_from_object = pose.table_from_object;
        let grasp_object = GraspObject::new(mesh)?;
        let analysis = analyse(&grasp_object, &table_from_object, &gripper, &config, seed)?;
        let body = PhysicsObject::from_grasp_object(&grasp_object, &config.shape)?;
        analysis
            .grasps
            .iter()
            .enumerate()
            .map(|(i, g)| {
                let label = g.physics_success.ok_or_else(|| Error::Evaluate {
                    problem: format!("{set}|{object}: the analysis ran no perturbed trials"),
                })?;
                let outcome = self.outcome((&body, &table_from_object), (&g.grasp, i), seed)?;
                Ok(LabelRecord {
                    set: set.to_string(),
                    object: object.to_string(),
                    group: group.to_string(),
                    robust_epsilon: g.quality.robust_epsilon,
                    robust: g.robust_label,
                    physics_rate: label.settled_rate(),
                    outcome_rate: outcome.settled_rate(),
                    outcome_failures: outcome.failures,
                })
            })
            .collect()
    }
}

/// A confusion table: [label +, held], [label +, failed], [label -, held], [label -, failed].
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Confusion(pub [usize; 4]);

impl Confusion {
    /// Counts one grasp.
    pub fn add(&mut self, label: bool, held: bool) {
        self.0[usize::from(!label) * 2 + usize::from(!held)] += 1;
    }

    /// The confusion tables of the robust, physics and both labels over `records`.
    pub fn of<'a>(records: impl Iterator<Item = &'a LabelRecord>) -> [Self; 3] {
        let mut tables = [Self::default(); 3];
        for (labels, held) in records.filter_map(LabelRecord::judged) {
            for (table, label) in tables.iter_mut().zip(labels) {
                table.add(label, held);
            }
        }
        tables
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use super::*;

    fn record(robust: bool, physics: Option<f64>, outcome: Option<f64>) -> LabelRecord {
        LabelRecord {
            set: "s".into(),
            object: "o".into(),
            group: "g".into(),
            robust_epsilon: 0.0,
            robust,
            physics_rate: physics,
            outcome_rate: outcome,
            outcome_failures: StageCounts::default(),
        }
    }

    #[test]
    fn the_tables_count_each_label_against_the_outcome_and_leave_out_unjudged_grasps() {
        let records = [
            record(true, Some(0.9), Some(0.8)),  // robust +, physics +: held
            record(true, Some(0.2), Some(0.1)),  // robust +, physics -: failed
            record(false, Some(0.5), Some(0.4)), // robust -, physics + (a half): failed
            record(false, None, Some(1.0)),      // never settled: not judged
        ];
        let [robust, physics, both] = Confusion::of(records.iter());
        assert_eq!(robust.0, [1, 1, 0, 1]);
        assert_eq!(physics.0, [1, 1, 0, 1]);
        assert_eq!(both.0, [1, 0, 0, 2]);
    }

    #[test]
    fn an_object_is_labelled_with_the_same_bits_twice_and_its_outcomes_are_rates() {
        let mesh =
            mvgrasp_geometry::objects::generate(mvgrasp_geometry::objects::Category::Box, 31, 0)
                .unwrap()
                .mesh;
        let suite = LabelSuite {
            grasps: 3,
            trials: 3,
            outcome_trials: 4,
        };
        let a = suite.run(("s", "box", "box"), mesh.clone(), 0).unwrap();
        let b = suite.run(("s", "box", "box"), mesh, 0).unwrap();
        assert!(!a.is_empty());
        assert_eq!(a, b);
        for r in &a {
            for rate in [r.physics_rate, r.outcome_rate].into_iter().flatten() {
                assert!((0.0..=1.0).contains(&rate), "{r:?}");
            }
        }
    }
}
