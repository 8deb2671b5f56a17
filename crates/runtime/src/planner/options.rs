//! The options of a plan, shared by the `plan` command and the Python `Planner`, and the one
//! place that turns them into a policy and its settings: the network's default, fusion and the
//! virtual re-scoring, CEM, the hand check and the seed; for a rendered mesh also the camera,
//! how many views how far away, the resting pose, the physics check and whether depth is
//! rendered or predicted from rendered RGB views.

use mvgrasp_geometry::{Intrinsics, IntrinsicsPreset};
use mvgrasp_grasp::Gripper;
use mvgrasp_infer::Gqcnn;
use mvgrasp_planner::{
    CemParams, DepthSource, FusionParams, GqcnnPolicy, HoldProbability, MultiViewPlanner, Planner,
    PlannerKind, ScoredGrasp, ViewSetting, VirtualScorer, models,
};

use crate::error::{Error, Result};
use crate::planner::{DepthFrom, DepthPredictor, PlanParams, RgbInput, SensorPlanParams};

/// Views the multi-view planner fuses unless told otherwise (the seed paper's setting, the
/// first top-down).
pub const FUSED_VIEWS: usize = 5;

/// Where the chance to hold of a plan's best grasp comes from
/// ([`PlanOptions::chance_source`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChanceSource {
    /// The top-down GQ-CNN's quality mapped to the trial's outcomes on this depth source
    /// ([`HoldProbability`], `models/probability_topdown.json`).
    Mapped(DepthSource),
    /// The multi-view planner's quality, its ranker's modelled chance to hold
    /// ([`mvgrasp_planner::Ranker`], `models/ranker_fused.json`), mapped to the trial's
    /// outcomes of its best grasps on this depth source (`models/probability_fused.json`);
    /// `None`: settings no map was fitted for, the ranker's figure as it is.
    Ranker(Option<DepthSource>),
}

impl ChanceSource {
    /// The chance to hold of `best`, planned by a planner with this source; `None` when the
    /// multi-view planner's best was not ranked (no re-score).
    ///
    /// # Errors
    /// Only if a shipped map is broken (a test loads them).
    pub fn of(self, best: &ScoredGrasp) -> Result<Option<f32>> {
        Ok(match self {
            Self::Ranker(None) => best.virtual_quality.map(|_| best.quality),
            Self::Ranker(Some(depth)) => match best.virtual_quality {
                Some(_) => {
                    Some(HoldProbability::shipped(PlannerKind::MultiView)?.of(best.quality, depth))
                }
                None => None,
            },
            Self::Mapped(depth) => {
                Some(HoldProbability::shipped(PlannerKind::TopDown)?.of(best.quality, depth))
            }
        })
    }

    /// Where the figure comes from, in words for a summary.
    pub fn describe(self) -> &'static str {
        match self {
            Self::Ranker(None) => {
                "the ranker's model of the trial's outcomes (models/ranker_fused.json), not mapped: \
                 no map was fitted for these settings"
            }
            Self::Ranker(Some(_)) => {
                "the ranker's model of the trial's outcomes, mapped to its best grasps' outcomes \
                 on the development set: models/ranker_fused.json, models/probability_fused.json"
            }
            Self::Mapped(_) => {
                "the quality mapped to the trial's outcomes on the development set: \
                 models/probability_topdown.json"
            }
        }
    }
}

/// What a plan is asked to do (`plan`'s options; the Python `Planner`'s keywords).
#[derive(Clone, Debug, PartialEq)]
pub struct PlanOptions {
    /// The multi-view planner: views fused, every candidate's hand checked against all of them,
    /// the best re-scored on virtual views ([`MultiViewPlanner`]).
    pub fuse: bool,
    /// Dex-Net 2.0's cross-entropy method in each view.
    pub cem: bool,
    /// Reject candidates whose open hand meets the observed depth.
    pub hand_check: bool,
    /// Seeds the sampler (and, on a mesh, the cameras).
    pub seed: u64,
    /// On a mesh: the camera's intrinsics.
    pub camera: IntrinsicsPreset,
    /// On a mesh: plan in the first this many test views (with `depth_from` and no `fuse`:
    /// predict the depth of this many, plan in the first); `None`: the network's setting
    /// ([`ViewSetting`]), or [`FUSED_VIEWS`] when fusing or predicting depth.
    pub views: Option<usize>,
    /// On a mesh: the cameras' distance from the object, metres; `None`: the network's.
    pub distance_m: Option<f32>,
    /// On a mesh: the offered resting pose to put it in (0: the most probable).
    pub stable_pose: usize,
    /// On a mesh: run the rapier trial on the chosen grasp.
    pub physics: bool,
    /// On a mesh: render the views in colour and plan on depth predicted from them by this
    /// predictor; `None`: on the rendered depth. The depth is predicted from [`FUSED_VIEWS`]
    /// views (the first top-down) unless told otherwise, and without `fuse` the network plans
    /// in the top-down one alone, the views at its own distance (0.7 m for the top-down
    /// GQ-CNN), with `fuse` at the multi-view planner's 0.65 m (docs/depth-from-rgb.md:
    /// the top-down GQ-CNN's grasps on predicted depth held at least as often as the
    /// multi-view planner's).
    pub depth_from: Option<DepthFrom>,
    /// With `depth_from`: the views rendered with the photographic look
    /// ([`crate::scene::photoreal`]) instead of the flat one.
    pub photo: bool,
}

impl Default for PlanOptions {
    fn default() -> Self {
        Self {
            fuse: false,
            cem: false,
            hand_check: true,
            seed: 0,
            camera: IntrinsicsPreset::PhoxiS,
            views: None,
            distance_m: None,
            stable_pose: 0,
            physics: true,
            depth_from: None,
            photo: false,
        }
    }
}

impl PlanOptions {
    /// The depth source whose hold probability ([`mvgrasp_planner::HoldProbability`]) applies
    /// to the grasps of these options planned with the network `model` (its name): the shipped
    /// network of the planner ([`Self::default_model`]), no CEM, and on a mesh the settings the
    /// maps were fitted with (the planner's own views and distance, the default camera, the
    /// flat look) on rendered depth or the plane sweep's; `sensor`: a depth camera's image.
    /// `None` otherwise.
    pub fn hold_source(&self, model: &str, sensor: bool) -> Option<DepthSource> {
        if model != self.default_model() || self.cem {
            return None;
        }
        if sensor {
            return Some(DepthSource::Camera);
        }
        let views = self.views.is_none() && self.distance_m.is_none() && !self.photo;
        let camera = self.camera == IntrinsicsPreset::PhoxiS;
        match self.depth_from {
            _ if !(views && camera) => None,
            None => Some(DepthSource::Camera),
            Some(DepthFrom::Baseline) => Some(DepthSource::Sweep),
            Some(_) => None,
        }
    }

    /// Where the chance to hold of these options' best grasp comes from, planned with the
    /// network `model` (`sensor`: on a depth camera's image): the multi-view planner's ranker
    /// (without CEM), mapped where [`Self::hold_source`] has a map, or the top-down GQ-CNN's
    /// map where it has one.
    pub fn chance_source(&self, model: &str, sensor: bool) -> Option<ChanceSource> {
        let source = self.hold_source(model, sensor);
        match self.fuse {
            true if !self.cem => Some(ChanceSource::Ranker(source)),
            true => None,
            false => source.map(ChanceSource::Mapped),
        }
    }

    /// [`Self::chance_source`] of a plan over a folder of a camera's views (`plan
    /// --views-dir`): depth images, or RGB views whose depth `rgb` predicts. Only the
    /// multi-view planner has one there (the top-down maps were fitted on one view), mapped on
    /// depth images and on the plane sweep's depth.
    pub fn chance_source_on_views(
        &self,
        model: &str,
        rgb: Option<DepthFrom>,
    ) -> Option<ChanceSource> {
        let source = match rgb {
            None => Some(DepthSource::Camera),
            Some(DepthFrom::Baseline) => Some(DepthSource::Sweep),
            Some(_) => None,
        };
        match self.chance_source(model, true)? {
            ChanceSource::Ranker(Some(_)) => Some(ChanceSource::Ranker(source)),
            ChanceSource::Ranker(None) => Some(ChanceSource::Ranker(None)),
            ChanceSource::Mapped(_) => None,
        }
    }

    /// The shipped network these options plan with when none is named: the multi-view GQ-CNN
    /// when fusing (it proposes every view's candidates), else the top-down GQ-CNN.
    pub fn default_model(&self) -> &'static str {
        if self.fuse {
            models::MVGQCNN.name
        } else {
            models::GQCNN_TOPDOWN.name
        }
    }

    /// The planner around `net` for `gripper`: the multi-view planner with `net` proposing
    /// when fusing, else `net`'s policy alone.
    fn planner(&self, net: Gqcnn, gripper: &Gripper) -> Result<Planner> {
        let mut policy = GqcnnPolicy::new(net, gripper.max_opening_m)?;
        policy.cem = self.cem.then(CemParams::default);
        Ok(if self.fuse {
            let scorer = VirtualScorer::shipped(gripper.max_opening_m)?;
            MultiViewPlanner::new(policy, scorer).into()
        } else {
            policy.into()
        })
    }

    /// The planner, gripper and settings of a plan on depth images (a sensor's, or views with
    /// their cameras).
    ///
    /// # Errors
    /// A network that does not fit the gripper, or shipped weights that cannot be loaded.
    pub fn on_depth(&self, net: Gqcnn) -> Result<(Planner, Gripper, SensorPlanParams)> {
        let gripper = PlanParams::default().labels.gripper;
        let planner = self.planner(net, &gripper)?;
        let params = SensorPlanParams {
            hand_check: self.hand_check,
            seed: self.seed,
            fusion: self.fuse.then(FusionParams::default),
            ..Default::default()
        };
        Ok((planner, gripper, params))
    }

    /// The planner and settings of a plan on a mesh rendered on the table ([`super::plan_grasp`]).
    ///
    /// # Errors
    /// [`Error::PlanOption`] for no views, more than the test views, or a distance that is
    /// not a positive length; and [`PlanOptions::on_depth`]'s.
    pub fn on_mesh(&self, net: Gqcnn) -> Result<(Planner, PlanParams)> {
        let mut setting = ViewSetting::for_pose_inputs(net.architecture().pose_inputs);
        if self.fuse {
            // The multi-view planner's views, which also give depth from RGB its stereo.
            setting = ViewSetting {
                views: FUSED_VIEWS,
                distance_m: ViewSetting::for_pose_inputs(2).distance_m,
            };
        } else if self.depth_from.is_some() {
            // Depth from RGB for a network planning in one view: as many views for the stereo,
            // at the planning network's own distance (the top-down GQ-CNN's 0.7 m: its grasps
            // held 64% of the time on the baseline's depth there, 62% at the multi-view
            // planner's 0.65 m; docs/depth-from-rgb.md).
            setting.views = FUSED_VIEWS;
        }
        let mut params = PlanParams {
            intrinsics: Intrinsics::preset(self.camera),
            stable_pose: self.stable_pose,
            seed: self.seed,
            physics: self.physics,
            hand_check: self.hand_check,
            ..Default::default()
        };
        let views = self.views.unwrap_or(setting.views);
        if !(1..=params.views.count).contains(&views) {
            return Err(Error::PlanOption {
                name: "views",
                value: views.to_string(),
                expected: "1 to 10 (the test views)",
            });
        }
        let distance_m = self.distance_m.unwrap_or(setting.distance_m);
        if !(distance_m.is_finite() && distance_m > 0.0) {
            return Err(Error::PlanOption {
                name: "distance_m",
                value: distance_m.to_string(),
                expected: "a distance in metres above 0",
            });
        }
        if let Some(from) = self.depth_from {
            if views < 2 {
                return Err(Error::PlanOption {
                    name: "views",
                    value: views.to_string(),
                    expected: "at least 2 views to predict depth from RGB",
                });
            }
            let depth = DepthPredictor::shipped(from)?;
            params.depth_from_rgb = Some(RgbInput {
                depth: if self.fuse {
                    depth
                } else {
                    depth.for_one_view()
                },
                per_face: false,
                photo: self.photo,
            });
            // Without fusion every view predicts depth, and the network plans in the first,
            // top-down one.
            params.plan_views = (!self.fuse).then_some(1);
        }
        params.max_views = views;
        params.views.radius_m = distance_m;
        if self.fuse || self.depth_from.is_some() {
            // The views spread over the whole cap (the first top-down), not the first of ten.
            params.views.count = views;
        }
        if self.fuse {
            params.fusion = Some(FusionParams::default());
        }
        let planner = self.planner(net, &params.labels.gripper)?;
        Ok((planner, params))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Which map a plan's chance to hold comes from: each planner's own, only with the
    /// settings it was fitted with, and never for CEM.
    #[test]
    fn the_chance_comes_from_the_map_fitted_for_the_settings() {
        let fused = PlanOptions {
            fuse: true,
            ..PlanOptions::default()
        };
        let mvgqcnn = models::MVGQCNN.name;
        let topdown = models::GQCNN_TOPDOWN.name;
        let with = |depth_from| PlanOptions {
            depth_from,
            ..fused.clone()
        };
        let ranker = |source| Some(ChanceSource::Ranker(source));
        assert_eq!(
            fused.chance_source(mvgqcnn, false),
            ranker(Some(DepthSource::Camera))
        );
        assert_eq!(
            with(Some(DepthFrom::Baseline)).chance_source(mvgqcnn, false),
            ranker(Some(DepthSource::Sweep))
        );
        // No map for other predictors, views, cameras or another network: the ranker as it is.
        assert_eq!(
            with(Some(DepthFrom::Lsm)).chance_source(mvgqcnn, false),
            ranker(None)
        );
        let three = PlanOptions {
            views: Some(3),
            ..fused.clone()
        };
        assert_eq!(three.chance_source(mvgqcnn, false), ranker(None));
        assert_eq!(fused.chance_source(topdown, false), ranker(None));
        let cem = PlanOptions {
            cem: true,
            ..fused.clone()
        };
        assert_eq!(cem.chance_source(mvgqcnn, false), None);
        // The top-down planner: its own map, with its own network only.
        let plain = PlanOptions::default();
        assert_eq!(
            plain.chance_source(topdown, false),
            Some(ChanceSource::Mapped(DepthSource::Camera))
        );
        assert_eq!(
            plain.chance_source(topdown, true),
            Some(ChanceSource::Mapped(DepthSource::Camera))
        );
        assert_eq!(plain.chance_source(mvgqcnn, false), None);
        // A folder of views: the multi-view planner's map, by what gave the depth.
        assert_eq!(
            fused.chance_source_on_views(mvgqcnn, None),
            ranker(Some(DepthSource::Camera))
        );
        assert_eq!(
            fused.chance_source_on_views(mvgqcnn, Some(DepthFrom::Baseline)),
            ranker(Some(DepthSource::Sweep))
        );
        assert_eq!(
            fused.chance_source_on_views(mvgqcnn, Some(DepthFrom::Mvs)),
            ranker(None)
        );
        assert_eq!(plain.chance_source_on_views(topdown, None), None);
    }
}
