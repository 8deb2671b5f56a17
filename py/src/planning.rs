//! Planning from NumPy: a depth image (and its camera matrix, optional mask and pose) to the
//! ranked grasps, as `plan --depth ... --json` prints them (`grasps.json`).

use std::path::Path;

use mvgrasp::grasps_file::{GraspsFile, WorldFrame};
use mvgrasp::planner::{
    CemParams, DepthImage, GqcnnPolicy, PlanParams, SensorPlanParams, View, models, plan_on_view,
};
use mvgrasp_geometry::{Camera, Intrinsics, Pose3, pose_from_rows};
use mvgrasp_infer::Gqcnn;
use numpy::{PyReadonlyArray2, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::convert::to_python;
use crate::errors::{WeightsError, pipeline_error};

/// Plans a grasp on one depth image, as `plan --depth` does, and returns the content of
/// `grasps.json` (format `mvgrasp-grasps/1`) as a dict.
///
/// `depth`: float32 metres, shape (H, W) or (H, W, 1); NaN, infinities and 0 are missing.
/// `k`: the 3x3 camera matrix (no skew). `mask`: bool (H, W), the object's pixels.
/// `world_from_camera`: the camera's 4x4 pose (rows); without it the world is put on the table
/// fitted in the image. `model`: a shipped network's name or an export's `NAME.json`.
/// Raises `ValueError` for arrays of the wrong shape or values, `TypeError` for other dtypes,
/// `mvgrasp.PlanningError` when there is no table or nothing on it, `mvgrasp.WeightsError`
/// for a network that cannot be loaded.
#[pyfunction]
#[pyo3(signature = (depth, k, *, mask = None, world_from_camera = None, model = "gqcnn_small_topdown", cem = false, hand_check = true, seed = 0))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_depth<'py>(
    py: Python<'py>,
    depth: PyReadonlyArrayDyn<'py, f32>,
    k: PyReadonlyArray2<'py, f64>,
    mask: Option<PyReadonlyArray2<'py, bool>>,
    world_from_camera: Option<PyReadonlyArray2<'py, f64>>,
    model: &str,
    cem: bool,
    hand_check: bool,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let shape = depth.as_array().shape().to_vec();
    let (height, width) = match shape[..] {
        [h, w] | [h, w, 1] => (h, w),
        _ => {
            return Err(PyValueError::new_err(format!(
                "depth: shape {shape:?}, expected (H, W) or (H, W, 1)"
            )));
        }
    };
    let values: Vec<f32> = depth.as_array().iter().copied().collect();
    let k = k.as_array();
    if k.shape() != [3, 3] {
        return Err(PyValueError::new_err(format!(
            "k: shape {:?}, expected (3, 3)",
            k.shape()
        )));
    }
    if k[[0, 1]] != 0.0 || k[[1, 0]] != 0.0 || [k[[2, 0]], k[[2, 1]], k[[2, 2]]] != [0.0, 0.0, 1.0]
    {
        return Err(PyValueError::new_err(
            "k: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew)",
        ));
    }
    let (w, h) = (
        u32::try_from(width).map_err(|e| PyValueError::new_err(format!("depth: {e}")))?,
        u32::try_from(height).map_err(|e| PyValueError::new_err(format!("depth: {e}")))?,
    );
    let intrinsics = Intrinsics::new(
        k[[0, 0]] as f32,
        k[[1, 1]] as f32,
        k[[0, 2]] as f32,
        k[[1, 2]] as f32,
        w,
        h,
        0.1,
        2.0,
    )
    .map_err(|e| PyValueError::new_err(format!("k: {e}")))?;
    let mask = match mask {
        Some(m) => {
            let m = m.as_array();
            if m.shape() != [height, width] {
                return Err(PyValueError::new_err(format!(
                    "mask: shape {:?}, expected the depth's ({height}, {width})",
                    m.shape()
                )));
            }
            Some(m.iter().copied().collect::<Vec<bool>>())
        }
        None => None,
    };
    let pose = match world_from_camera {
        Some(p) => {
            let p = p.as_array();
            if p.shape() != [4, 4] {
                return Err(PyValueError::new_err(format!(
                    "world_from_camera: shape {:?}, expected (4, 4)",
                    p.shape()
                )));
            }
            let rows = std::array::from_fn(|i| std::array::from_fn(|j| p[[i, j]]));
            Some(
                pose_from_rows(rows)
                    .map_err(|e| PyValueError::new_err(format!("world_from_camera: {e}")))?,
            )
        }
        None => None,
    };
    let net = match models::shipped(model) {
        Some(shipped) => shipped.load().map_err(|e| e.to_string()),
        None => Gqcnn::load(Path::new(model)).map_err(|e| e.to_string()),
    }
    .map_err(|e| WeightsError::new_err(format!("{model}: {e}")))?;
    let file = py.detach(|| -> mvgrasp::Result<GraspsFile> {
        let gripper = PlanParams::default().labels.gripper()?;
        let mut policy = GqcnnPolicy::new(net, gripper.max_opening_m)?;
        policy.cem = cem.then(CemParams::default);
        let camera = Camera {
            intrinsics,
            world_from_camera: pose.unwrap_or(Pose3::IDENTITY),
        };
        let mut view = View::new(0, camera, DepthImage::new(intrinsics, values)?)?;
        if let Some(pixels) = mask {
            view = view.with_mask(mvgrasp::planner::Mask::new(w, h, pixels)?)?;
        }
        let params = SensorPlanParams {
            hand_check,
            seed,
            ..Default::default()
        };
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
