//! Depth from RGB views: the one interface every method implements ([`DepthFromRgb`]: views
//! with their cameras in, per view a depth image and, where the method has one, a per-pixel
//! confidence out), and the shipped methods as `plan --depth-from` names them
//! ([`DepthFrom`], [`DepthPredictor`]).
//!
//! Each method lives in its own module and implements the trait there: the plane sweep
//! ([`crate::stereo`], on [`SweepParams`]), the sweep refined by a network
//! ([`crate::sweep_refiner`], on [`RefinedSweep`]), the learned multi-view stereo network
//! ([`crate::mvs`], on [`MvsDepth`]) and the Learnt Stereo Machine ([`crate::lsm`], on
//! `mvgrasp_infer::Lsm`). A new method is a type that implements [`DepthFromRgb`] in its own
//! file; [`crate::planner::plan_on_rgb_views`] and [`crate::planner::predict_views`] take any
//! of them, the caller's own included. To be one of `plan`'s `--depth-from` names it also gets
//! a [`DepthFrom`] variant and a line in [`DepthPredictor::shipped`].
//!
//! The contract: one [`PredictedDepth`] per view, in order, each at its camera's resolution;
//! depth in metres along the optical axis, 0 where the method gives none (the planner's fused
//! model treats it as unseen space, which the hand may not enter); with a mask, the pixels off
//! the object hold the table plane's depth, as every shipped method gives them.
//!
//! ```
//! use mvgrasp_runtime::Result;
//! use mvgrasp_runtime::depth_from_rgb::{DepthFromRgb, PredictedDepth, RgbView};
//!
//! /// Depth that another program predicted for the same views, as a method.
//! struct Precomputed {
//!     depth_m: Vec<Vec<f32>>,
//! }
//!
//! impl DepthFromRgb for Precomputed {
//!     fn name(&self) -> &str {
//!         "precomputed"
//!     }
//!
//!     fn predict(&self, views: &[RgbView]) -> Result<Vec<PredictedDepth>> {
//!         Ok(self.depth_m
//!             .iter()
//!             .take(views.len())
//!             .map(|d| PredictedDepth { depth_m: d.clone(), confidence: None })
//!             .collect())
//!     }
//! }
//! // Then: mvgrasp_runtime::planner::plan_on_rgb_views(&planner, &gripper, &views, &params,
//! //     &method)
//! ```

use std::sync::Arc;

use mvgrasp_infer::{Lsm, Parallelism};
use mvgrasp_planner::models;

use crate::error::{Error, Result};
use crate::mvs::MvsDepth;
pub use crate::stereo::RgbView;
use crate::stereo::SweepParams;
use crate::sweep_refiner::{RefinedSweep, Unsure};

/// One view's predicted depth, at its camera's resolution.
#[derive(Clone, Debug, PartialEq)]
pub struct PredictedDepth {
    /// Metres along the optical axis, row-major; 0 where the method gives no depth.
    pub depth_m: Vec<f32>,
    /// The method's confidence in `[0, 1]` per pixel, where it has one (the networks that
    /// predict one: the sweep refiner, the multi-view stereo network); `None` for the others.
    pub confidence: Option<Vec<f32>>,
}

impl PredictedDepth {
    /// A method's depth and per-pixel confidence.
    pub fn with_confidence(depth_m: Vec<f32>, confidence: Vec<f32>) -> Self {
        Self {
            depth_m,
            confidence: Some(confidence),
        }
    }

    /// A method's depth, without a confidence.
    pub fn depth_only(depth_m: Vec<f32>) -> Self {
        Self {
            depth_m,
            confidence: None,
        }
    }
}

/// A way to predict depth from posed RGB views.
pub trait DepthFromRgb: Send + Sync {
    /// Its name in summaries (the shipped ones: `plan --depth-from`'s names).
    fn name(&self) -> &str;

    /// The depth of every view, in the order of `views` (see the module's contract).
    ///
    /// # Errors
    /// The method's own: too few views for it, cameras it cannot place, a network's errors.
    fn predict(&self, views: &[RgbView]) -> Result<Vec<PredictedDepth>>;
}

/// `method`'s prediction of `views`, checked against the contract: one view each, at its
/// camera's size, the confidence (where given) as large.
///
/// # Errors
/// The method's; [`Error::Stereo`] naming the method where its output breaks the contract.
pub fn checked(method: &dyn DepthFromRgb, views: &[RgbView]) -> Result<Vec<PredictedDepth>> {
    let predicted = method.predict(views)?;
    let broken = |problem: String| Error::Stereo {
        problem: format!("depth from RGB by {}: {problem}", method.name()),
    };
    if predicted.len() != views.len() {
        return Err(broken(format!(
            "{} depth images for {} views",
            predicted.len(),
            views.len()
        )));
    }
    for (i, (view, depth)) in views.iter().zip(&predicted).enumerate() {
        let k = view.camera.intrinsics;
        let pixels = k.width as usize * k.height as usize;
        let confidence = depth.confidence.as_ref().map_or(pixels, Vec::len);
        if depth.depth_m.len() != pixels || confidence != pixels {
            return Err(broken(format!(
                "view {i}: {} depths and {confidence} confidences for a {} x {} camera",
                depth.depth_m.len(),
                k.width,
                k.height
            )));
        }
    }
    Ok(predicted)
}

/// Which depth predictor (`plan --depth-from`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DepthFrom {
    /// The learned multi-view stereo network, the shipped weights ([`crate::mvs`]).
    Mvs,
    /// The Learnt Stereo Machine, the shipped weights ([`crate::lsm`]).
    Lsm,
    /// The classical baseline: silhouette carving and a plane sweep ([`crate::stereo`]).
    Baseline,
    /// The plane sweep and its learned refinement, the shipped weights
    /// ([`crate::sweep_refiner`]).
    Refined,
}

impl std::str::FromStr for DepthFrom {
    type Err = String;

    fn from_str(name: &str) -> std::result::Result<Self, String> {
        match name {
            "mvs" => Ok(Self::Mvs),
            "lsm" => Ok(Self::Lsm),
            "baseline" => Ok(Self::Baseline),
            "refined" => Ok(Self::Refined),
            other => Err(format!("{other:?}, expected baseline, refined, mvs or lsm")),
        }
    }
}

impl DepthFrom {
    /// The predictor of `plan`'s default run and of `plan --rgb` without `--depth-from`: the
    /// one whose depth gave the grasps that held most often on held-out objects
    /// (docs/depth-from-rgb.md). The refined sweep gives better depth, but its grasps have not
    /// yet measured apart from the sweep's: on the development set (94 built-in objects from
    /// index 50, the top-down GQ-CNN, 5 views 0.7 m away) 80% held on its depth against 77%,
    /// on the default mug over ten seeds 6 against 7.
    pub const DEFAULT: Self = Self::Baseline;

    /// Its name on the command line and in summaries.
    pub fn name(self) -> &'static str {
        match self {
            Self::Mvs => "mvs",
            Self::Lsm => "lsm",
            Self::Baseline => "baseline",
            Self::Refined => "refined",
        }
    }
}

/// A depth predictor, ready to run: the baseline's settings or a loaded network.
#[derive(Clone, Debug)]
pub enum DepthPredictor {
    /// The classical baseline with these settings.
    Baseline(SweepParams),
    /// A Learnt Stereo Machine.
    Lsm(Arc<Lsm>),
    /// A multi-view stereo network; its pixels of lower confidence are left missing.
    Mvs(MvsDepth),
    /// The plane sweep refined by a network.
    Refined(RefinedSweep),
}

/// The shipped sweep refiner's confidence threshold: an object pixel below it is left missing
/// (unseen space for the multi-view planner) or, for a network planning in one view
/// ([`DepthPredictor::for_one_view`]), takes the visual hull's depth. The confidence is the
/// network's probability that the pixel is within 3 mm (docs/depth-from-rgb.md has its
/// reliability table).
pub const REFINED_MIN_CONFIDENCE: f32 = 0.5;

/// The shipped multi-view stereo network's confidence threshold: pixels below it are left
/// missing (unseen space for the planner). 0, every pixel kept: the shipped network's
/// confidence is not calibrated (of the object pixels it gives 0.9 or more, 28% are within
/// 5 mm; docs/depth-from-rgb.md).
pub const MVS_MIN_CONFIDENCE: f32 = 0.0;

impl PartialEq for DepthPredictor {
    /// The same baseline settings, or the same loaded network.
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Self::Baseline(a), Self::Baseline(b)) => a == b,
            (Self::Lsm(a), Self::Lsm(b)) => Arc::ptr_eq(a, b),
            (Self::Mvs(a), Self::Mvs(b)) => {
                Arc::ptr_eq(&a.net, &b.net) && a.min_confidence == b.min_confidence
            }
            (Self::Refined(a), Self::Refined(b)) => {
                Arc::ptr_eq(&a.net, &b.net)
                    && a.min_confidence == b.min_confidence
                    && a.unsure == b.unsure
            }
            _ => false,
        }
    }
}

impl DepthPredictor {
    /// This predictor for a network that plans in one predicted view (the default run's
    /// top-down GQ-CNN): the sweep's object pixels that no second view confirms take the visual
    /// hull's depth instead of being left missing (the network was trained on complete depth
    /// images and scores holes as nothing; the hull never lies beyond the surface, so the hand
    /// check stays on the safe side). Measured on the development set (94 built-in objects
    /// from index 50, the top-down GQ-CNN on 5 views at 0.7 m): 77% of objects held with the
    /// hull, 70% keeping the unconfirmed winners, 79% on rendered depth. The refined sweep's
    /// unsure pixels take the hull's depth the same way ([`Unsure::Hull`]); the other networks
    /// are returned as they are.
    #[must_use]
    pub fn for_one_view(self) -> Self {
        match self {
            Self::Baseline(sweep) => Self::Baseline(SweepParams {
                hull_where_unconfirmed: true,
                ..sweep
            }),
            Self::Refined(refined) => Self::Refined(RefinedSweep {
                unsure: Unsure::Hull,
                ..refined
            }),
            other => other,
        }
    }

    /// The shipped predictor of `from`: the baseline with its default settings, or the shipped
    /// LSM on every thread of rayon's pool (as the baseline runs).
    ///
    /// # Errors
    /// Only if the shipped weights are broken (a test loads them).
    pub fn shipped(from: DepthFrom) -> Result<Self> {
        Ok(match from {
            DepthFrom::Baseline => Self::Baseline(SweepParams::default()),
            DepthFrom::Lsm => Self::Lsm(Arc::new(
                models::LSM
                    .load()?
                    .with_parallelism(Parallelism::all_threads()),
            )),
            DepthFrom::Mvs => Self::Mvs(MvsDepth {
                net: Arc::new(
                    models::MVS
                        .load()?
                        .with_parallelism(Parallelism::all_threads()),
                ),
                min_confidence: MVS_MIN_CONFIDENCE,
            }),
            DepthFrom::Refined => Self::Refined(RefinedSweep {
                net: Arc::new(
                    models::SWEEP_REFINER
                        .load()?
                        .with_parallelism(Parallelism::all_threads()),
                ),
                min_confidence: REFINED_MIN_CONFIDENCE,
                unsure: Unsure::Missing,
            }),
        })
    }

    /// Which kind it is.
    pub fn kind(&self) -> DepthFrom {
        match self {
            Self::Baseline(_) => DepthFrom::Baseline,
            Self::Lsm(_) => DepthFrom::Lsm,
            Self::Mvs(_) => DepthFrom::Mvs,
            Self::Refined(_) => DepthFrom::Refined,
        }
    }

    /// The method it runs.
    pub fn method(&self) -> &dyn DepthFromRgb {
        match self {
            Self::Baseline(sweep) => sweep,
            Self::Lsm(lsm) => lsm.as_ref(),
            Self::Mvs(mvs) => mvs,
            Self::Refined(refined) => refined,
        }
    }

    /// The depth of every view at its resolution (metres; 0: not predicted), in order.
    ///
    /// # Errors
    /// The method's ([`DepthFromRgb::predict`]).
    pub fn depths(&self, views: &[RgbView]) -> Result<Vec<Vec<f32>>> {
        Ok(checked(self, views)?
            .into_iter()
            .map(|view| view.depth_m)
            .collect())
    }
}

impl DepthFromRgb for DepthPredictor {
    fn name(&self) -> &str {
        self.kind().name()
    }

    fn predict(&self, views: &[RgbView]) -> Result<Vec<PredictedDepth>> {
        self.method().predict(views)
    }
}

#[cfg(test)]
mod tests {
    #![allow(clippy::unwrap_used)]

    use mvgrasp_geometry::{Camera, Intrinsics, Vec3};

    use super::*;
    use crate::planner::predict_views;

    /// A method of the caller's own: every pixel at one depth, or a broken output.
    struct Flat {
        depth_m: f32,
        broken: Option<&'static str>,
    }

    impl DepthFromRgb for Flat {
        fn name(&self) -> &str {
            "flat"
        }

        fn predict(&self, views: &[RgbView]) -> Result<Vec<PredictedDepth>> {
            let mut out: Vec<PredictedDepth> = views
                .iter()
                .map(|v| {
                    let k = v.camera.intrinsics;
                    let pixels = k.width as usize * k.height as usize;
                    PredictedDepth {
                        depth_m: vec![self.depth_m; pixels],
                        confidence: Some(vec![0.5; pixels]),
                    }
                })
                .collect();
            match self.broken {
                Some("one view short") => {
                    out.pop();
                }
                Some("small depth") => {
                    out[1].depth_m.pop();
                }
                Some("small confidence") => out[0].confidence = Some(vec![1.0; 3]),
                _ => {}
            }
            Ok(out)
        }
    }

    fn views() -> Vec<RgbView> {
        let k = Intrinsics::new(40.0, 40.0, 15.5, 11.5, 32, 24, 0.05, 3.0).unwrap();
        [Vec3::new(0.0, 0.0, 0.6), Vec3::new(0.3, 0.0, 0.5)]
            .map(|eye| RgbView {
                camera: Camera::look_at(k, eye, Vec3::ZERO, Vec3::Y).unwrap(),
                rgb: vec![[128; 3]; 32 * 24],
                mask: None,
            })
            .to_vec()
    }

    #[test]
    fn the_planner_takes_a_method_of_the_callers_own() {
        let method = Flat {
            depth_m: 0.55,
            broken: None,
        };
        let planned = predict_views(&views(), &method).unwrap();
        assert_eq!(planned.len(), 2);
        assert!(planned[1].depth.as_slice().iter().all(|&d| d == 0.55));
    }

    #[test]
    fn an_output_that_breaks_the_contract_is_refused_by_the_methods_name() {
        for (broken, needle) in [
            ("one view short", "1 depth images for 2 views"),
            ("small depth", "view 1: 767 depths"),
            ("small confidence", "view 0: 768 depths and 3 confidences"),
        ] {
            let method = Flat {
                depth_m: 0.5,
                broken: Some(broken),
            };
            let err = predict_views(&views(), &method).unwrap_err().to_string();
            assert!(
                err.contains("depth from RGB by flat") && err.contains(needle),
                "{broken}: {err}"
            );
        }
    }

    #[test]
    fn each_shipped_method_names_itself_and_runs_behind_the_interface() {
        for from in [DepthFrom::Baseline, DepthFrom::Refined] {
            let predictor = DepthPredictor::shipped(from).unwrap();
            assert_eq!(predictor.name(), from.name());
            assert_eq!(predictor.method().name(), from.name());
            let predicted = checked(&predictor, &views()).unwrap();
            assert_eq!(predicted.len(), 2);
            assert_eq!(
                predicted[0].confidence.is_some(),
                from == DepthFrom::Refined,
                "{from:?}"
            );
        }
    }
}
