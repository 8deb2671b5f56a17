//! Cameras: intrinsics (files, presets), camera layouts on the hemisphere, and depth images to
//! points. A camera crosses the binding as a dict `{k, width, height, world_from_camera}`: the
//! 3x3 matrix, the image size and the 4x4 pose (OpenCV frame: x right, y down, z forward).

use std::path::PathBuf;

use mvgrasp_geometry::{Camera, HemisphereLayout, Intrinsics, IntrinsicsPreset, Pose3, Vec3};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::arrays::{array_of, depth_of, intrinsics_of, k_array, optional_pose, pose_array};
use crate::convert::to_python;
use crate::errors::camera_error;

/// Reads a Berkeley `.intr` file (JSON with `_fx _fy _cx _cy _width _height`); the intrinsics
/// as a dict (`fx`, `fy`, `cx`, `cy` in pixels, `width`, `height`, `z_near_m`, `z_far_m`).
/// Raises `mvgrasp.CameraError` naming the file when it is missing, unparsable or invalid.
#[pyfunction]
pub(crate) fn load_intrinsics(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let intrinsics = Intrinsics::from_intr_file(&path).map_err(camera_error)?;
    to_python(py, &intrinsics)
}

/// The intrinsics of a preset (`phoxi_s`, the datasets' camera; `primesense`;
/// `realsense_d435`), as `load_intrinsics` returns them. Raises `mvgrasp.CameraError` for
/// another name.
#[pyfunction]
#[pyo3(signature = (name = "phoxi_s"))]
pub(crate) fn intrinsics_preset<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    let preset: IntrinsicsPreset = name.parse().map_err(camera_error)?;
    to_python(py, &Intrinsics::preset(preset))
}

/// A camera as the dict the binding uses.
fn camera_dict<'py>(py: Python<'py>, camera: &Camera) -> PyResult<Bound<'py, PyDict>> {
    let dict = PyDict::new(py);
    dict.set_item("k", k_array(py, &camera.intrinsics))?;
    dict.set_item("width", camera.intrinsics.width)?;
    dict.set_item("height", camera.intrinsics.height)?;
    dict.set_item(
        "world_from_camera",
        pose_array(py, &camera.world_from_camera),
    )?;
    Ok(dict)
}

/// Cameras on a spherical cap above the table, looking at `target` (world, z up from the
/// table), as the datasets place them: `count` views `radius_m` away, elevations stratified
/// between `min_elevation_deg` and `max_elevation_deg` in equal-area bands, azimuths spread by
/// the golden angle, both jittered from `seed`; the first exactly top-down when
/// `include_top_down`. The defaults are the seed paper's 10 test views. Each camera is a dict
/// `{k, width, height, world_from_camera}` (`intrinsics`: a preset's name). Raises
/// `mvgrasp.CameraError` for a bad layout or preset.
#[pyfunction]
// pyo3 writes a tuple default as `...` in `__text_signature__`: the signature is spelled out.
#[pyo3(
    signature = (count = 10, radius_m = 0.5, min_elevation_deg = 15.0, max_elevation_deg = 85.0, include_top_down = true, target = (0.0, 0.0, 0.0), intrinsics = "phoxi_s", seed = 0),
    text_signature = "(count=10, radius_m=0.5, min_elevation_deg=15.0, max_elevation_deg=85.0, include_top_down=True, target=(0.0, 0.0, 0.0), intrinsics='phoxi_s', seed=0)"
)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn hemisphere_cameras<'py>(
    py: Python<'py>,
    count: usize,
    radius_m: f32,
    min_elevation_deg: f32,
    max_elevation_deg: f32,
    include_top_down: bool,
    target: (f32, f32, f32),
    intrinsics: &str,
    seed: u64,
) -> PyResult<Bound<'py, PyList>> {
    let preset: IntrinsicsPreset = intrinsics.parse().map_err(camera_error)?;
    let layout = HemisphereLayout {
        count,
        radius_m,
        min_elevation_rad: min_elevation_deg.to_radians(),
        max_elevation_rad: max_elevation_deg.to_radians(),
        include_top_down,
    };
    let target = Vec3::new(target.0, target.1, target.2);
    let cameras = layout
        .cameras(Intrinsics::preset(preset), target, seed)
        .map_err(camera_error)?;
    let list = PyList::empty(py);
    for camera in &cameras {
        list.append(camera_dict(py, camera)?)?;
    }
    Ok(list)
}

/// The 3-D points of a depth image, one per valid pixel (z > 0 and finite) in row-major order,
/// as an `(N, 3)` float32 array: in the camera frame, or in the world with `world_from_camera`.
/// `depth`: float32 metres, `(H, W)` or `(H, W, 1)`; `k`: the 3x3 camera matrix.
#[pyfunction]
#[pyo3(signature = (depth, k, world_from_camera = None))]
pub(crate) fn depth_to_points<'py>(
    py: Python<'py>,
    depth: Bound<'py, PyAny>,
    k: Bound<'py, PyAny>,
    world_from_camera: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let (width, height, values) = depth_of("depth", &depth)?;
    let camera = camera_of(&k, "depth", width, height, world_from_camera.as_ref())?;
    let points = py
        .detach(|| camera.depth_to_world_points(&values))
        .map_err(|e| PyValueError::new_err(format!("depth: {e}")))?;
    let n = points.len();
    let flat: Vec<f32> = points.iter().flat_map(|p| p.to_array()).collect();
    Ok(PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any())
}

/// The camera of a 3x3 `k`, its image size and its pose (identity when `None`).
fn camera_of(
    k: &Bound<'_, PyAny>,
    image: &str,
    width: u32,
    height: u32,
    world_from_camera: Option<&Bound<'_, PyAny>>,
) -> PyResult<Camera> {
    Ok(Camera {
        intrinsics: intrinsics_of("k", k, image, width, height)?,
        world_from_camera: optional_pose("world_from_camera", world_from_camera)?
            .unwrap_or(Pose3::IDENTITY),
    })
}

/// The `(N, 2)` pixels (u right, v down) where world points `(N, 3)` project through the
/// camera (`k`, image size, pose); NaN for a point behind it.
#[pyfunction]
#[pyo3(signature = (points, k, width, height, world_from_camera = None))]
pub(crate) fn project_points<'py>(
    py: Python<'py>,
    points: Bound<'py, PyAny>,
    k: Bound<'py, PyAny>,
    width: u32,
    height: u32,
    world_from_camera: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let camera = camera_of(
        &k,
        "width x height",
        width,
        height,
        world_from_camera.as_ref(),
    )?;
    let p = array_of::<f64>("points", &points)?;
    let p = p.as_array();
    if p.ndim() != 2 || p.shape()[1] != 3 {
        return Err(PyValueError::new_err(format!(
            "points: shape {:?}, expected (N, 3)",
            p.shape()
        )));
    }
    let pixels: Vec<f64> = p
        .rows()
        .into_iter()
        .flat_map(|r| {
            let point = Vec3::new(r[0] as f32, r[1] as f32, r[2] as f32);
            camera
                .project(point)
                .map_or([f64::NAN; 2], |px| px.map(f64::from))
        })
        .collect();
    Ok(PyArray1::from_vec(py, pixels)
        .reshape([p.shape()[0], 2])?
        .into_any())
}

/// The `(N, 3)` world points at pixels `(N, 2)` and depths `(N,)` (metres along the optical
/// axis) of the camera (`k`, image size, pose).
#[pyfunction]
#[pyo3(signature = (pixels, depths, k, width, height, world_from_camera = None))]
pub(crate) fn unproject_pixels<'py>(
    py: Python<'py>,
    pixels: Bound<'py, PyAny>,
    depths: Bound<'py, PyAny>,
    k: Bound<'py, PyAny>,
    width: u32,
    height: u32,
    world_from_camera: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let camera = camera_of(
        &k,
        "width x height",
        width,
        height,
        world_from_camera.as_ref(),
    )?;
    let (px, d) = (
        array_of::<f64>("pixels", &pixels)?,
        array_of::<f64>("depths", &depths)?,
    );
    let (px, d) = (px.as_array(), d.as_array());
    if px.ndim() != 2 || px.shape()[1] != 2 || d.shape() != [px.shape()[0]] {
        return Err(PyValueError::new_err(format!(
            "pixels {:?} and depths {:?}: expected (N, 2) and (N,)",
            px.shape(),
            d.shape()
        )));
    }
    let points: Vec<f64> = px
        .rows()
        .into_iter()
        .zip(d.iter())
        .flat_map(|(r, &depth)| {
            camera
                .unproject(r[0] as f32, r[1] as f32, depth as f32)
                .to_array()
                .map(f64::from)
        })
        .collect();
    Ok(PyArray1::from_vec(py, points)
        .reshape([px.shape()[0], 3])?
        .into_any())
}
