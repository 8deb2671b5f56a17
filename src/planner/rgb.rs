//! Planning on RGB views (`plan --rgb DIR`): the views' depth predicted from the images and
//! their cameras, then the multi-view planner on it, as on a depth camera's views.
//!
//! A folder holds `cameras.json` (the cameras, posed in the table frame, as `render` writes
//! them) and per camera `NNN_rgb.png` (8-bit RGB), optionally `NNN_mask.png` (the object's
//! pixels; a `render` dataset's `train` or `test` folder is one). Depth comes from the
//! learned multi-view stereo network ([`crate::mvs`], the shipped `models/mvs_small`), the
//! Learnt Stereo Machine ([`crate::lsm`], the shipped `models/lsm_small`) or the classical
//! baseline ([`crate::stereo`]): a [`DepthPredictor`].

use std::path::Path;
use std::sync::Arc;
use std::time::Instant;

use mvgrasp_infer::{Lsm, Mvs, Parallelism};
use mvgrasp_planner::{DepthImage, Mask, Planner, View, models};

use crate::error::{Error, Result};
use crate::lsm::lsm_depths;
use crate::mvs::mvs_depths;
use crate::planner::sensor::{mismatch, read_cameras_json, render_conventions};
use crate::planner::{SensorPlanParams, ViewsPlanReport, plan_on_views};
use crate::sensor_files::{read_mask_of, read_rgb};
use crate::stereo::{RgbView, SweepParams, sweep_depths};
use crate::sweep_refiner::{RefinedSweep, Unsure};

/// Reads the RGB views of `dir` (see the module docs).
///
/// # Errors
/// One line naming the file: `cameras.json` missing or not a list of cameras; an image
/// missing for a camera, or one past the cameras; an image that is not 8-bit RGB or not its
/// camera's size; a mask of another size, or one with no object pixel (the camera does not
/// see the object); a camera looking away from the table.
pub fn read_rgb_dir(dir: &Path) -> Result<Vec<RgbView>> {
    let (cameras_path, cameras) = read_cameras_json(dir)?;
    let extra = dir.join(format!("{:03}_rgb.png", cameras.len()));
    if extra.is_file() {
        return Err(mismatch(
            &extra,
            format!(
                "{} lists {} cameras, but this is image {}",
                cameras_path.display(),
                cameras.len(),
                cameras.len()
            ),
        ));
    }
    let (_, object_id) = render_conventions(dir)?;
    let mut views = Vec::with_capacity(cameras.len());
    for (i, camera) in cameras.into_iter().enumerate() {
        let path = dir.join(format!("{i:03}_rgb.png"));
        if !path.is_file() {
            return Err(mismatch(
                &path,
                format!("camera {i} of {} has no image", cameras_path.display()),
            ));
        }
        let (width, height, rgb) = read_rgb(&path)?;
        let k = camera.intrinsics;
        if (k.width, k.height) != (width, height) {
            return Err(mismatch(
                &path,
                format!(
                    "{width} x {height} pixels, but its camera in {} is {} x {}",
                    cameras_path.display(),
                    k.width,
                    k.height
                ),
            ));
        }
        if camera.optical_axis().z >= 0.0 {
            return Err(mismatch(
                &cameras_path,
                format!("camera {i} looks up, away from the table (z up in the world)"),
            ));
        }
        let mask_path = dir.join(format!("{i:03}_mask.png"));
        let mask = if mask_path.is_file() {
            // A mask with no object pixel: the camera does not see the object.
            Some(read_mask_of(&mask_path, width, height, object_id)?.into_pixels())
        } else {
            None
        };
        views.push(RgbView { camera, rgb, mask });
    }
    Ok(views)
}

/// The planner's views of RGB views: each camera with its predicted depth (and its mask).
///
/// # Errors
/// See [`DepthPredictor::depths`].
pub fn predict_views(rgb: &[RgbView], predictor: &DepthPredictor) -> Result<Vec<View>> {
    let depths = predictor.depths(rgb)?;
    rgb.iter()
        .zip(depths)
        .enumerate()
        .map(|(i, (view, depth))| {
            let k = view.camera.intrinsics;
            let mut planned = View::new(i, view.camera, DepthImage::new(k, depth)?)?;
            if let Some(mask) = &view.mask {
                planned = planned.with_mask(Mask::new(k.width, k.height, mask.clone())?)?;
            }
            Ok(planned)
        })
        .collect()
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
    Mvs {
        /// The network.
        net: Arc<Mvs>,
        /// Pixels whose confidence is below this are left missing (0).
        min_confidence: f32,
    },
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
            (
                Self::Mvs {
                    net: a,
                    min_confidence: x,
                },
                Self::Mvs {
                    net: b,
                    min_confidence: y,
                },
            ) => Arc::ptr_eq(a, b) && x == y,
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
            DepthFrom::Mvs => Self::Mvs {
                net: Arc::new(
                    models::MVS
                        .load()?
                        .with_parallelism(Parallelism::all_threads()),
                ),
                min_confidence: MVS_MIN_CONFIDENCE,
            },
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
            Self::Mvs { .. } => DepthFrom::Mvs,
            Self::Refined(_) => DepthFrom::Refined,
        }
    }

    /// The depth of every view at its resolution (metres; 0: not predicted), in order.
    ///
    /// # Errors
    /// See [`sweep_depths`] and [`lsm_depths`].
    pub fn depths(&self, views: &[RgbView]) -> Result<Vec<Vec<f32>>> {
        match self {
            Self::Baseline(sweep) => Ok(sweep_depths(views, sweep)?
                .into_iter()
                .map(|d| d.depth_m)
                .collect()),
            Self::Lsm(lsm) => lsm_depths(lsm, views),
            Self::Mvs {
                net,
                min_confidence,
            } => Ok(mvs_depths(net, views, *min_confidence)?
                .into_iter()
                .map(|view| view.depth_m)
                .collect()),
            Self::Refined(refined) => Ok(refined
                .depths(views)?
                .into_iter()
                .map(|view| view.depth_m)
                .collect()),
        }
    }
}

/// What [`plan_on_rgb_dir`] found: the plan on the predicted depth, and the prediction's time.
#[derive(Clone, Debug)]
pub struct RgbPlanReport {
    /// The plan, as on a depth camera's views (its views hold the predicted depth).
    pub plan: ViewsPlanReport,
    /// Seconds spent predicting depth.
    pub depth_s: f64,
}

/// Plans on the RGB views of `dir` ([`read_rgb_dir`], then [`plan_on_rgb_views`]).
///
/// # Errors
/// See [`read_rgb_dir`] and [`plan_on_rgb_views`].
pub fn plan_on_rgb_dir(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    dir: &Path,
    params: &SensorPlanParams,
    predictor: &DepthPredictor,
) -> Result<RgbPlanReport> {
    plan_on_rgb_views(planner, gripper, &read_rgb_dir(dir)?, params, predictor)
}

/// Plans on RGB views: their depth predicted ([`predict_views`]), then [`plan_on_views`].
///
/// # Errors
/// See [`DepthPredictor::depths`] and [`plan_on_views`].
pub fn plan_on_rgb_views(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    rgb: &[RgbView],
    params: &SensorPlanParams,
    predictor: &DepthPredictor,
) -> Result<RgbPlanReport> {
    if rgb.len() < 2 {
        return Err(Error::Stereo {
            problem: format!(
                "planning on RGB views needs at least 2 views, got {} (one predicted view leaves \
                 the object's far side unseen)",
                rgb.len()
            ),
        });
    }
    let started = Instant::now();
    let views = predict_views(rgb, predictor)?;
    let depth_s = started.elapsed().as_secs_f64();
    Ok(RgbPlanReport {
        plan: plan_on_views(planner, gripper, views, params)?,
        depth_s,
    })
}
