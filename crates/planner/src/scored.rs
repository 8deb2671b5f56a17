//! What a plan is made of: a candidate with its scores ([`ScoredGrasp`]) and why candidates were
//! rejected ([`Rejection`], [`Rejections`]). Every stage of the planner (the policies, the hand
//! check, the re-scoring, the ranker) imports these and none of the others' types.

use mvgrasp_grasp::{Grasp, ImageGrasp};
use serde::Serialize;

/// A candidate with the network's score.
#[derive(Clone, Copy, Debug, PartialEq, Serialize)]
pub struct ScoredGrasp {
    /// The view it was found in.
    pub view: usize,
    /// The grasp in that view's image.
    pub image: ImageGrasp,
    /// The grasp in the world.
    pub grasp: Grasp,
    /// The view's angle to the table plane (the multi-view GQ-CNN's theta), radians.
    pub theta_rad: f32,
    /// The network's probability that the grasp is robust: the planning network's on the view,
    /// or, where the candidate was re-scored ([`crate::VirtualScorer`]), the re-scoring
    /// network's on its virtual view. Candidates are ranked by it.
    pub quality: f32,
    /// The planning network's score on the view, where `quality` is a re-score.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub view_quality: Option<f32>,
    /// The re-scoring network's score on the candidate's virtual view, where `quality` is the
    /// ranker's probability built on it ([`crate::Ranker`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub virtual_quality: Option<f32>,
    /// Found by the virtual scorer's own network ([`crate::VirtualScorer::propose`]), not the
    /// policy's.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub by_scorer: bool,
    /// Sampled on the fused model's points ([`crate::cloud_sampler`]), not in a view's image:
    /// `view` is the view that looks most nearly along its approach and `image` the grasp as
    /// that view sees it.
    #[serde(skip_serializing_if = "std::ops::Not::not")]
    pub from_cloud: bool,
}

impl ScoredGrasp {
    /// Which quota of the per-view hand check and re-scoring the candidate counts against:
    /// its view's, the scorer's own candidates apart from the policy's, and those sampled on
    /// the fused model all in one.
    pub fn quota(&self) -> (usize, bool) {
        if self.from_cloud {
            (usize::MAX, false)
        } else {
            (self.view, self.by_scorer)
        }
    }
}

/// The angle between `grasp`'s approach and straight down, radians.
pub fn tilt_rad(grasp: &Grasp) -> f32 {
    (-grasp.approach().z).clamp(-1.0, 1.0).acos()
}

/// Why a candidate was rejected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Rejection {
    /// The open hand, on its approach or at the grasp, meets an observed point.
    HandMeetsObservedDepth,
    /// The open hand, on its approach or at the grasp, enters space that no view has seen
    /// (behind every view's surface: the object's hidden side, the table in its shadow).
    HandEntersUnknownSpace,
    /// The open hand reaches below the table.
    HandBelowTable,
    /// A contact's pixel has no depth in the view the grasp was planned in.
    ContactOffSurface,
    /// A contact's pixel is not on the object's mask (within 2 pixels) in the view the grasp
    /// was planned in.
    ContactOffObject,
}

/// How many candidates were rejected, by reason.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize)]
pub struct Rejections {
    /// See [`Rejection::HandMeetsObservedDepth`].
    pub hand_meets_observed_depth: usize,
    /// See [`Rejection::HandEntersUnknownSpace`].
    pub hand_enters_unknown_space: usize,
    /// See [`Rejection::HandBelowTable`].
    pub hand_below_table: usize,
    /// See [`Rejection::ContactOffSurface`].
    pub contact_off_surface: usize,
    /// See [`Rejection::ContactOffObject`].
    pub contact_off_object: usize,
}

impl Rejections {
    /// Counts one rejection.
    pub fn add(&mut self, rejection: Rejection) {
        match rejection {
            Rejection::HandMeetsObservedDepth => self.hand_meets_observed_depth += 1,
            Rejection::HandEntersUnknownSpace => self.hand_enters_unknown_space += 1,
            Rejection::HandBelowTable => self.hand_below_table += 1,
            Rejection::ContactOffSurface => self.contact_off_surface += 1,
            Rejection::ContactOffObject => self.contact_off_object += 1,
        }
    }

    /// The reasons, in words with their counts ("none" when there is none).
    pub fn describe(&self) -> String {
        let reasons: Vec<String> = [
            (
                "the open hand meets observed depth",
                self.hand_meets_observed_depth,
            ),
            (
                "it enters space no view has seen",
                self.hand_enters_unknown_space,
            ),
            ("it reaches below the table", self.hand_below_table),
            (
                "contacts off the observed surface",
                self.contact_off_surface,
            ),
            ("contacts off the object", self.contact_off_object),
        ]
        .into_iter()
        .filter(|&(_, n)| n > 0)
        .map(|(why, n)| format!("{why} ({n})"))
        .collect();
        if reasons.is_empty() {
            "none".into()
        } else {
            reasons.join(", ")
        }
    }

    /// All of them.
    pub fn total(&self) -> usize {
        self.hand_meets_observed_depth
            + self.hand_enters_unknown_space
            + self.hand_below_table
            + self.contact_off_surface
            + self.contact_off_object
    }
}
