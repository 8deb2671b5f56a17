//! The planners `plan` runs: one GQ-CNN's policy over the views ([`GqcnnPolicy`]), or the
//! multi-view planner ([`MultiViewPlanner`]), which holds the policy that proposes candidates in
//! every view and the [`VirtualScorer`] that re-scores the best of them on the fused views and
//! ranks them by their modelled chance to hold.

use mvgrasp_grasp::Gripper;

use crate::depth_image::View;
use crate::error::Result;
use crate::fusion::Fusion;
use crate::plan::Plan;
use crate::policy::GqcnnPolicy;
use crate::virtual_view::VirtualScorer;

/// The multi-view planner: candidates from every view by `proposer`, the scorer's own from the
/// top-down views and from the fused model's points, the hand check against the views and the
/// fused model, then the best of each view re-scored on virtual views and ranked.
#[derive(Debug)]
pub struct MultiViewPlanner {
    /// Proposes candidates in every view.
    pub proposer: GqcnnPolicy,
    /// Proposes its own, re-scores and ranks.
    pub scorer: VirtualScorer,
}

impl MultiViewPlanner {
    /// The planner of `proposer` and `scorer`; each view samples only
    /// `scorer.params.grasps_per_view` grasp axes (the re-score, not the proposer's own score,
    /// picks the grasp; fewer proposals cost less and held as often on the development set).
    pub fn new(mut proposer: GqcnnPolicy, scorer: VirtualScorer) -> Self {
        proposer.sampler.num_grasps = scorer.params.grasps_per_view;
        Self { proposer, scorer }
    }

    /// The whole plan over `views`. With the views fused: the proposer's plan, the scorer's own
    /// top-down proposals and those on the fused points merged in, the hand check (unless
    /// `hand_check` is false) until `keep` (at least the scorer's candidates per view) of each
    /// view survive, so that every view's best are re-scored, then the re-scoring. Without
    /// `fusion` there is nothing to re-score on: the proposer's checked plan.
    ///
    /// # Errors
    /// See [`GqcnnPolicy::plan`]; a network error while re-scoring.
    pub fn plan_checked(
        &self,
        views: &[View],
        fusion: Option<&Fusion>,
        gripper: &Gripper,
        hand_check: bool,
        keep: usize,
        seed: u64,
    ) -> Result<Plan> {
        let Some(fusion) = fusion else {
            return self
                .proposer
                .plan_checked(views, None, gripper, hand_check, keep, seed);
        };
        let scorer = &self.scorer;
        let mut plan = self.proposer.plan(views, seed)?;
        plan.merge(scorer.propose(views, seed)?);
        plan.merge(scorer.propose_on_cloud(fusion, views, seed)?);
        if hand_check {
            plan.reject_colliding_each_view(
                views,
                Some(fusion),
                gripper,
                scorer.params.candidates_per_view.max(keep),
            );
        }
        scorer.rescore(&mut plan, fusion, seed)?;
        Ok(plan)
    }
}

/// A planner: one network's policy, or the multi-view planner (each boxed: a policy holds its
/// network, a kilobyte).
#[derive(Debug)]
pub enum Planner {
    /// One GQ-CNN over the views, each candidate ranked by its score in its view (Dex-Net 2.0's
    /// policy on one top-down view; the seed paper's multi-view policy on several).
    Single(Box<GqcnnPolicy>),
    /// The multi-view planner.
    MultiView(Box<MultiViewPlanner>),
}

impl Planner {
    /// The plan over `views`, checked ([`GqcnnPolicy::plan_checked`],
    /// [`MultiViewPlanner::plan_checked`]).
    ///
    /// # Errors
    /// See those.
    pub fn plan_checked(
        &self,
        views: &[View],
        fusion: Option<&Fusion>,
        gripper: &Gripper,
        hand_check: bool,
        keep: usize,
        seed: u64,
    ) -> Result<Plan> {
        match self {
            Self::Single(policy) => {
                policy.plan_checked(views, fusion, gripper, hand_check, keep, seed)
            }
            Self::MultiView(planner) => {
                planner.plan_checked(views, fusion, gripper, hand_check, keep, seed)
            }
        }
    }

    /// The policy that proposes the candidates in every view.
    pub fn policy(&self) -> &GqcnnPolicy {
        match self {
            Self::Single(policy) => policy,
            Self::MultiView(planner) => &planner.proposer,
        }
    }

    /// See [`Self::policy`].
    pub fn policy_mut(&mut self) -> &mut GqcnnPolicy {
        match self {
            Self::Single(policy) => policy,
            Self::MultiView(planner) => &mut planner.proposer,
        }
    }

    /// The multi-view planner's scorer; `None` for a single policy.
    pub fn scorer(&self) -> Option<&VirtualScorer> {
        match self {
            Self::Single(_) => None,
            Self::MultiView(planner) => Some(&planner.scorer),
        }
    }
}

impl From<GqcnnPolicy> for Planner {
    fn from(policy: GqcnnPolicy) -> Self {
        Self::Single(Box::new(policy))
    }
}

impl From<MultiViewPlanner> for Planner {
    fn from(planner: MultiViewPlanner) -> Self {
        Self::MultiView(Box::new(planner))
    }
}
