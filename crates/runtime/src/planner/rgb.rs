//! Planning on RGB views (`plan --rgb DIR`): the views' depth predicted from the images and
//! their cameras, then the multi-view planner on it, as on a depth camera's views.
//!
//! A folder holds `cameras.json` (the cameras, posed in the table frame, as `render` writes
//! them) and per camera `NNN_rgb.png` (8-bit RGB), optionally `NNN_mask.png` (the object's
//! pixels; a `render` dataset's `train` or `test` folder is one). Depth comes from any
//! [`DepthFromRgb`] method: one of the shipped ones ([`DepthPredictor`]) or the caller's own.

use std::path::Path;
use std::time::Instant;

use mvgrasp_planner::{DepthImage, Mask, Planner, View};

use crate::depth_from_rgb::DepthFromRgb;
pub use crate::depth_from_rgb::{DepthFrom, DepthPredictor};
use crate::error::{Error, Result};
use crate::planner::sensor::{mismatch, read_cameras_json, render_conventions};
use crate::planner::{SensorPlanParams, ViewsPlanReport, plan_on_views};
use crate::sensor_files::{read_mask_of, read_rgb};
use crate::stereo::RgbView;

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
/// The method's ([`DepthFromRgb::predict`]); a method that gives a view of the wrong size, or
/// the wrong number of views, is refused by name.
pub fn predict_views(rgb: &[RgbView], predictor: &dyn DepthFromRgb) -> Result<Vec<View>> {
    let depths = crate::depth_from_rgb::checked(predictor, rgb)?;
    rgb.iter()
        .zip(depths)
        .enumerate()
        .map(|(i, (view, predicted))| {
            let k = view.camera.intrinsics;
            let mut planned = View::new(i, view.camera, DepthImage::new(k, predicted.depth_m)?)?;
            if let Some(mask) = &view.mask {
                planned = planned.with_mask(Mask::new(k.width, k.height, mask.clone())?)?;
            }
            Ok(planned)
        })
        .collect()
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
    predictor: &dyn DepthFromRgb,
) -> Result<RgbPlanReport> {
    plan_on_rgb_views(planner, gripper, &read_rgb_dir(dir)?, params, predictor)
}

/// Plans on RGB views: their depth predicted ([`predict_views`]), then [`plan_on_views`].
///
/// # Errors
/// See [`predict_views`] and [`plan_on_views`].
pub fn plan_on_rgb_views(
    planner: &Planner,
    gripper: &mvgrasp_grasp::Gripper,
    rgb: &[RgbView],
    params: &SensorPlanParams,
    predictor: &dyn DepthFromRgb,
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
