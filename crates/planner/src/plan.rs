//! A plan: every scored candidate of every view, best first, and the hand check that prunes
//! them ([`Plan::reject_colliding`]).

use mvgrasp_grasp::Gripper;
use serde::Serialize;

use crate::depth_image::View;
use crate::fusion::Fusion;
use crate::hand_check::check_hand;
use crate::scored::{Rejections, ScoredGrasp};

/// What the planner found in each view and overall.
#[derive(Clone, Debug, Serialize)]
pub struct Plan {
    /// Every scored candidate of every view, best first (ties: lower view, then sampling
    /// order), less those [`Plan::reject_colliding`] dropped.
    pub candidates: Vec<ScoredGrasp>,
    /// Candidates per view, as sampled.
    pub candidates_per_view: Vec<usize>,
    /// The candidates dropped by [`Plan::reject_colliding`], by reason.
    pub rejections: Rejections,
}

impl Plan {
    /// Checks the candidates best first against every view and, where given, the views fused
    /// ([`check_hand`]: the open hand on its approach and at the grasp must meet no observed
    /// point, nor space no view has seen, the contacts must lie on observed surface), dropping
    /// those that fail, until `keep` have survived; the rest stay in order, unchecked. The
    /// rejections are counted in [`Plan::rejections`].
    pub fn reject_colliding(
        &mut self,
        views: &[View],
        fusion: Option<&Fusion>,
        gripper: &Gripper,
        keep: usize,
    ) {
        self.reject_until(views, fusion, gripper, keep, false);
    }

    /// [`Plan::reject_colliding`] until `keep` of each view (and of each view's candidates
    /// found by a virtual scorer, apart: [`ScoredGrasp::quota`]) have survived.
    pub fn reject_colliding_each_view(
        &mut self,
        views: &[View],
        fusion: Option<&Fusion>,
        gripper: &Gripper,
        keep: usize,
    ) {
        self.reject_until(views, fusion, gripper, keep, true);
    }

    fn reject_until(
        &mut self,
        views: &[View],
        fusion: Option<&Fusion>,
        gripper: &Gripper,
        keep: usize,
        each_view: bool,
    ) {
        let mut kept = Vec::with_capacity(self.candidates.len());
        // Survivors overall, or per quota.
        let mut survivors = std::collections::HashMap::<(usize, bool), usize>::new();
        for candidate in std::mem::take(&mut self.candidates) {
            let slot = if each_view {
                candidate.quota()
            } else {
                (0, false)
            };
            let survivors = survivors.entry(slot).or_default();
            if *survivors >= keep {
                kept.push(candidate);
                continue;
            }
            match check_hand(&candidate, views, fusion, gripper) {
                Some(rejection) => self.rejections.add(rejection),
                None => {
                    *survivors += 1;
                    kept.push(candidate);
                }
            }
        }
        self.candidates = kept;
    }

    /// Adds `extra` candidates (another network's, say) and ranks all of them again, best
    /// first (ties: the earlier first).
    pub fn merge(&mut self, extra: Vec<ScoredGrasp>) {
        for c in &extra {
            if let Some(n) = self.candidates_per_view.get_mut(c.view) {
                *n += 1;
            }
        }
        self.candidates.extend(extra);
        self.candidates
            .sort_by(|a, b| b.quality.total_cmp(&a.quality));
    }

    /// The best grasp, if any view had a candidate.
    pub fn best(&self) -> Option<&ScoredGrasp> {
        self.candidates.first()
    }

    /// The best grasp found in `view`.
    pub fn best_in_view(&self, view: usize) -> Option<&ScoredGrasp> {
        self.candidates.iter().find(|c| c.view == view)
    }
}
