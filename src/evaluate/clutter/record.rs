//! What a clutter round records: its scene, its cameras and every attempt's outcome.

use serde::{Deserialize, Serialize};

use super::{ClutterScene, DEFAULT_CAMERA};

/// What came of one attempt.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Outcome {
    /// Held through the shake, alone: taken away.
    Held,
    /// Failed at this phase of the trial.
    Failed(String),
    /// The planner returned no grasp: the round ends.
    NoGrasp,
    /// The object nearest the grasp did not stay at rest, twice: taken away uncounted.
    Unsettled,
}

/// One attempt of a round.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Attempt {
    /// The object nearest the grasp's centre (`None` when there was no grasp).
    pub object: Option<String>,
    /// Objects on the table before it.
    pub objects_left: usize,
    /// The planner's quality of its grasp.
    pub quality: Option<f32>,
    /// What came of it.
    pub outcome: Outcome,
    /// How far the object's centre of mass had risen when the trial ended, metres (`None`
    /// without a trial): on a failure after the close, whether the object itself came up (a
    /// neighbour that came with it failed the phase) or slipped out.
    #[serde(default)]
    pub lift_m: Option<f32>,
}

/// One round: its scene and every attempt.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RoundRecord {
    /// How the objects were set.
    pub scene: ClutterScene,
    /// The number of depth views planned on.
    pub views: usize,
    /// The round's index (its scene's seed).
    pub round: usize,
    /// The cameras' intrinsics preset.
    #[serde(default = "phoxi")]
    pub camera: String,
    /// Their distance from the table's centre, metres.
    #[serde(default = "seventy_cm")]
    pub distance_m: f32,
    /// The depth-from-RGB method that predicted the views' depth (`plan --depth-from`'s
    /// name); `None`: rendered depth.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub depth_from: Option<String>,
    /// Objects on the table once the scene was set (a pile's that fell out not counted).
    pub objects: usize,
    /// Objects that left the workspace as the others settled after a grasp (not cleared).
    pub fell_out: usize,
    /// The attempts, in order.
    pub attempts: Vec<Attempt>,
}

fn phoxi() -> String {
    DEFAULT_CAMERA.0.name().to_string()
}

fn seventy_cm() -> f32 {
    DEFAULT_CAMERA.1
}

impl RoundRecord {
    /// Grasps tried in the trial.
    pub fn tried(&self) -> usize {
        self.attempts
            .iter()
            .filter(|a| matches!(a.outcome, Outcome::Held | Outcome::Failed(_)))
            .count()
    }

    /// Grasps that held (objects cleared).
    pub fn held(&self) -> usize {
        self.count(&Outcome::Held)
    }

    /// Objects taken away uncounted.
    pub fn unsettled(&self) -> usize {
        self.count(&Outcome::Unsettled)
    }

    fn count(&self, outcome: &Outcome) -> usize {
        self.attempts
            .iter()
            .filter(|a| a.outcome == *outcome)
            .count()
    }
}
