//! Planning from NumPy: depth images (with their camera matrices, optional masks and poses) to
//! the ranked grasps, as `plan --depth ... --json` and `plan --views-dir ... --json` print them
//! (`grasps.json`).

use mvgrasp::grasps_file::{GraspsFile, WorldFrame};
use mvgrasp::planner::{
    CemParams, DepthImage, FusionParams, GqcnnPolicy, Mask, PlanParams, SensorPlanParams, View,
    VirtualScorer, models, plan_on_view, plan_on_views,
};
use mvgrasp_geometry::{Camera, Pose3};
use mvgrasp_infer::Gqcnn;
use numpy::{PyReadonlyArray2, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::{depth_of, intrinsics_of, pose_of};
use crate::convert::to_python;
use crate::errors::pipeline_error;
use crate::networks::load_model;

/// A mask's pixels, which must be the depth's size.
fn mask_of(
    name: &str,
    mask: &PyReadonlyArray2<'_, bool>,
    width: u32,
    height: u32,
) -> PyResult<Vec<bool>> {
    let m = mask.as_array();
    if m.shape() != [height as usize, width as usize] {
        return Err(PyValueError::new_err(format!(
            "{name}: shape {:?}, expected the depth's ({height}, {width})",
            m.shape()
        )));
    }
    Ok(m.iter().copied().collect())
}

/// The network `model` names (a shipped one or an export's JSON); `None`: the planner's
/// default, the multi-view GQ-CNN when fusing, else the top-down GQ-CNN.
fn network(model: Option<&str>, fuse: bool) -> PyResult<Gqcnn> {
    load_model(model.unwrap_or(if fuse {
        models::MVGQCNN.name
    } else {
        models::GQCNN_TOPDOWN.name
    }))
}

/// The policy and settings of `plan` with these options.
fn planner(
    net: Gqcnn,
    fuse: bool,
    cem: bool,
    hand_check: bool,
    seed: u64,
) -> mvgrasp::Result<(GqcnnPolicy, mvgrasp::grasp::Gripper, SensorPlanParams)> {
    let gripper = PlanParams::default().labels.gripper()?;
    let mut policy = GqcnnPolicy::new(net, gripper.max_opening_m)?;
    policy.cem = cem.then(CemParams::default);
    if fuse {
        policy.fuse_with(VirtualScorer::shipped(gripper.max_opening_m)?);
    }
    let params = SensorPlanParams {
        hand_check,
        seed,
        fusion: fuse.then(FusionParams::default),
        ..Default::default()
    };
    Ok((policy, gripper, params))
}

/// Plans a grasp on one depth image, as `plan --depth` does, and returns the content of
/// `grasps.json` (format `mvgrasp-grasps/1`) as a dict.
///
/// `depth`: float32 metres, shape (H, W) or (H, W, 1); NaN, infinities and 0 are missing.
/// `k`: the 3x3 camera matrix (no skew). `mask`: bool (H, W), the object's pixels.
/// `world_from_camera`: the camera's 4x4 pose (rows); without it the world is put on the table
/// fitted in the image. `model`: a shipped network's name or an export's `NAME.json`. `fuse`:
/// the multi-view planner's checks and re-scoring (`plan --fuse`). Raises `ValueError` for
/// arrays of the wrong shape or values, `TypeError` for other dtypes, `mvgrasp.PlanningError`
/// when there is no table or nothing on it, `mvgrasp.WeightsError` for a network that cannot be
/// loaded.
#[pyfunction]
#[pyo3(signature = (depth, k, *, mask = None, world_from_camera = None, model = None, fuse = false, cem = false, hand_check = true, seed = 0))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_depth<'py>(
    py: Python<'py>,
    depth: PyReadonlyArrayDyn<'py, f32>,
    k: PyReadonlyArray2<'py, f64>,
    mask: Option<PyReadonlyArray2<'py, bool>>,
    world_from_camera: Option<PyReadonlyArray2<'py, f64>>,
    model: Option<&str>,
    fuse: bool,
    cem: bool,
    hand_check: bool,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let (w, h, values) = depth_of("depth", &depth)?;
    let intrinsics = intrinsics_of("k", &k, w, h)?;
    let mask = mask.map(|m| mask_of("mask", &m, w, h)).transpose()?;
    let pose = world_from_camera
        .map(|p| pose_of("world_from_camera", &p))
        .transpose()?;
    let net = network(model, fuse)?;
    let file = py.detach(|| -> mvgrasp::Result<GraspsFile> {
        let (policy, gripper, params) = planner(net, fuse, cem, hand_check, seed)?;
        let camera = Camera {
            intrinsics,
            world_from_camera: pose.unwrap_or(Pose3::IDENTITY),
        };
        let mut view = View::new(0, camera, DepthImage::new(intrinsics, values)?)?;
        if let Some(pixels) = mask {
            view = view.with_mask(Mask::new(w, h, pixels)?)?;
        }
        let report = plan_on_view(&policy, &gripper, view, pose.is_some(), &params)?;
        let frame = if pose.is_some() {
            WorldFrame::Given
        } else {
            WorldFrame::Estimated
        };
        Ok(GraspsFile::new(
            frame,
            &[report.view.camera],
            &report.top,
            report.rejections,
            Some(report.table),
        ))
    });
    to_python(py, &file.map_err(pipeline_error)?)
}

/// Plans a grasp over several depth images of one scene, as `plan --views-dir` does, and
/// returns the content of `grasps.json` as a dict (its frame: the cameras' given one).
///
/// `depths`: one float32 (H, W) image per view (metres); `ks`: their 3x3 camera matrices;
/// `world_from_cameras`: their 4x4 poses in one world frame (with `fuse`, its z up from the
/// table); `masks`: per view a bool (H, W) mask of the object or `None`. The options are
/// `plan_depth`'s. Raises `ValueError` when the lists' lengths differ or for a bad array (the
/// message names it, e.g. `depths[2]`), and `plan_depth`'s errors.
#[pyfunction]
#[pyo3(signature = (depths, ks, world_from_cameras, *, masks = None, model = None, fuse = false, cem = false, hand_check = true, seed = 0))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_views<'py>(
    py: Python<'py>,
    depths: Vec<PyReadonlyArrayDyn<'py, f32>>,
    ks: Vec<PyReadonlyArray2<'py, f64>>,
    world_from_cameras: Vec<PyReadonlyArray2<'py, f64>>,
    masks: Option<Vec<Option<PyReadonlyArray2<'py, bool>>>>,
    model: Option<&str>,
    fuse: bool,
    cem: bool,
    hand_check: bool,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let n = depths.len();
    if n == 0
        || ks.len() != n
        || world_from_cameras.len() != n
        || masks.as_ref().is_some_and(|m| m.len() != n)
    {
        return Err(PyValueError::new_err(format!(
            "depths, ks, world_from_cameras (and masks): one per view, got {n}, {}, {}{}",
            ks.len(),
            world_from_cameras.len(),
            masks
                .as_ref()
                .map_or(String::new(), |m| format!(", {}", m.len()))
        )));
    }
    let mut inputs = Vec::with_capacity(n);
    for i in 0..n {
        let (w, h, values) = depth_of(&format!("depths[{i}]"), &depths[i])?;
        let intrinsics = intrinsics_of(&format!("ks[{i}]"), &ks[i], w, h)?;
        let pose = pose_of(&format!("world_from_cameras[{i}]"), &world_from_cameras[i])?;
        let mask = match masks.as_ref().and_then(|m| m[i].as_ref()) {
            Some(m) => Some(mask_of(&format!("masks[{i}]"), m, w, h)?),
            None => None,
        };
        inputs.push((intrinsics, values, pose, mask));
    }
    let net = network(model, fuse)?;
    let file = py.detach(|| -> mvgrasp::Result<GraspsFile> {
        let (policy, gripper, params) = planner(net, fuse, cem, hand_check, seed)?;
        let mut views = Vec::with_capacity(n);
        for (i, (intrinsics, values, pose, mask)) in inputs.into_iter().enumerate() {
            let camera = Camera {
                intrinsics,
                world_from_camera: pose,
            };
            let mut view = View::new(i, camera, DepthImage::new(intrinsics, values)?)?;
            if let Some(pixels) = mask {
                view = view.with_mask(Mask::new(intrinsics.width, intrinsics.height, pixels)?)?;
            }
            views.push(view);
        }
        let report = plan_on_views(&policy, &gripper, views, &params)?;
        let cameras: Vec<Camera> = report.views.iter().map(|v| v.camera).collect();
        Ok(GraspsFile::new(
            WorldFrame::Given,
            &cameras,
            &report.top,
            report.rejections,
            report.tables.first().copied(),
        ))
    });
    to_python(py, &file.map_err(pipeline_error)?)
}
