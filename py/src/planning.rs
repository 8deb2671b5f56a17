//! Planning from NumPy: depth images (with their camera matrices, optional masks and poses) to
//! the ranked grasps, as `plan --depth ... --json` and `plan --views-dir ... --json` print them
//! (`grasps.json`).

use mvgrasp::grasps_file::GraspsFile;
use mvgrasp::planner::{
    DepthFrom, DepthImage, DepthPredictor, Mask, PlanOptions, View, plan_grasp, plan_on_rgb_views,
    plan_on_view, plan_on_views,
};
use mvgrasp::stereo::RgbView;
use mvgrasp_geometry::{Camera, Pose3};
use mvgrasp_infer::Gqcnn;
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyString;

use crate::arrays::{
    array_of, depth_of, image_size, intrinsics_of, mask_of, mesh_of, optional_pose, pose_of,
};
use crate::convert::to_python;
use crate::errors::{camera_error, pipeline_error};
use crate::networks::load_model;
use crate::render::{backend_of, renderer};

/// Refuses lists of per-view inputs of different lengths (`names` and their lengths, the
/// first the views'), or fewer than `min` views.
fn one_per_view(names: &str, lengths: &[usize], min: usize) -> PyResult<()> {
    let n = lengths[0];
    if n >= min && lengths.iter().all(|&l| l == n) {
        return Ok(());
    }
    let got: Vec<String> = lengths.iter().map(usize::to_string).collect();
    Err(PyValueError::new_err(format!(
        "{names}: one per view and at least {min} {}, got {}",
        if min == 1 { "view" } else { "views" },
        got.join(", ")
    )))
}

/// `grasps.json`'s content as a dict, or with `as_json` its text, byte for byte what `plan
/// --out` writes.
fn grasps_output<'py>(
    py: Python<'py>,
    file: &GraspsFile,
    as_json: bool,
) -> PyResult<Bound<'py, PyAny>> {
    if as_json {
        let text = file.to_json().map_err(pipeline_error)?;
        Ok(PyString::new(py, &text).into_any())
    } else {
        to_python(py, file)
    }
}

/// The options every kind of plan shares.
fn options(fuse: bool, cem: bool, hand_check: bool, seed: u64) -> PlanOptions {
    PlanOptions {
        fuse,
        cem,
        hand_check,
        seed,
        ..PlanOptions::default()
    }
}

/// The network `model` names (a shipped one or an export's JSON); `None`: the default of
/// `options`.
fn network(model: Option<&str>, options: &PlanOptions) -> PyResult<Gqcnn> {
    load_model(model.unwrap_or(options.default_model()))
}

/// Plans a grasp on one depth image, as `plan --depth` does, and returns the content of
/// `grasps.json` (format `mvgrasp-grasps/1`) as a dict (with `as_json`, the file's text).
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
#[pyo3(signature = (depth, k, *, mask = None, world_from_camera = None, model = None, fuse = false, cem = false, hand_check = true, seed = 0, as_json = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_depth<'py>(
    py: Python<'py>,
    depth: Bound<'py, PyAny>,
    k: Bound<'py, PyAny>,
    mask: Option<Bound<'py, PyAny>>,
    world_from_camera: Option<Bound<'py, PyAny>>,
    model: Option<&str>,
    fuse: bool,
    cem: bool,
    hand_check: bool,
    seed: u64,
    as_json: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let (w, h, values) = depth_of("depth", &depth)?;
    let intrinsics = intrinsics_of("k", &k, "depth", w, h)?;
    let mask = mask.map(|m| mask_of("mask", &m, w, h)).transpose()?;
    let pose = optional_pose("world_from_camera", world_from_camera.as_ref())?;
    let options = options(fuse, cem, hand_check, seed);
    let net = network(model, &options)?;
    let file = py.detach(|| -> mvgrasp::Result<GraspsFile> {
        let (policy, gripper, params) = options.on_depth(net)?;
        let camera = Camera {
            intrinsics,
            world_from_camera: pose.unwrap_or(Pose3::IDENTITY),
        };
        let mut view = View::new(0, camera, DepthImage::new(intrinsics, values)?)?;
        if let Some(pixels) = mask {
            view = view.with_mask(Mask::new(w, h, pixels)?)?;
        }
        let report = plan_on_view(&policy, &gripper, view, pose.is_some(), &params)?;
        Ok(GraspsFile::of_sensor(&report))
    });
    grasps_output(py, &file.map_err(pipeline_error)?, as_json)
}

/// Plans a grasp over several depth images of one scene, as `plan --views-dir` does, and
/// returns the content of `grasps.json` as a dict (its frame: the cameras' given one; with
/// `as_json`, the file's text).
///
/// `depths`: one float32 (H, W) image per view (metres); `ks`: their 3x3 camera matrices;
/// `world_from_cameras`: their 4x4 poses in one world frame (with `fuse`, its z up from the
/// table); `masks`: per view a bool (H, W) mask of the object or `None`. The options are
/// `plan_depth`'s. Raises `ValueError` when the lists' lengths differ or for a bad array (the
/// message names it, e.g. `depths[2]`), and `plan_depth`'s errors.
#[pyfunction]
#[pyo3(signature = (depths, ks, world_from_cameras, *, masks = None, model = None, fuse = false, cem = false, hand_check = true, seed = 0, as_json = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_views<'py>(
    py: Python<'py>,
    depths: Vec<Bound<'py, PyAny>>,
    ks: Vec<Bound<'py, PyAny>>,
    world_from_cameras: Vec<Bound<'py, PyAny>>,
    masks: Option<Vec<Option<Bound<'py, PyAny>>>>,
    model: Option<&str>,
    fuse: bool,
    cem: bool,
    hand_check: bool,
    seed: u64,
    as_json: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let n = depths.len();
    let mut lengths = vec![n, ks.len(), world_from_cameras.len()];
    lengths.extend(masks.as_ref().map(Vec::len));
    one_per_view("depths, ks, world_from_cameras (and masks)", &lengths, 1)?;
    let mut inputs = Vec::with_capacity(n);
    for i in 0..n {
        let (w, h, values) = depth_of(&format!("depths[{i}]"), &depths[i])?;
        let intrinsics = intrinsics_of(&format!("ks[{i}]"), &ks[i], &format!("depths[{i}]"), w, h)?;
        let pose = pose_of(&format!("world_from_cameras[{i}]"), &world_from_cameras[i])?;
        let mask = match masks.as_ref().and_then(|m| m[i].as_ref()) {
            Some(m) => Some(mask_of(&format!("masks[{i}]"), m, w, h)?),
            None => None,
        };
        inputs.push((intrinsics, values, pose, mask));
    }
    let options = options(fuse, cem, hand_check, seed);
    let net = network(model, &options)?;
    let file = py.detach(|| -> mvgrasp::Result<GraspsFile> {
        let (policy, gripper, params) = options.on_depth(net)?;
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
        Ok(GraspsFile::of_views(&plan_on_views(
            &policy, &gripper, views, &params,
        )?))
    });
    grasps_output(py, &file.map_err(pipeline_error)?, as_json)
}

/// Plans a grasp on a mesh, as `plan --mesh` does: the object rests on the table in a stable
/// pose, its depth is rendered from the cameras, the policy plans, and the chosen grasp is
/// checked analytically and (with `physics`) in the rapier trial. Returns
/// `{"report": ..., "grasps_json": ..., "timings": ..., "hold_probability": ...}`: `plan
/// --json`'s plan report, the text of the `grasps.json` that `plan --out` writes, each stage's
/// seconds, and the best grasp's chance to hold where the planner has one (else `None`).
#[pyfunction]
#[pyo3(signature = (vertices, triangles, *, model = None, fuse = false, cem = false, hand_check = true, seed = 0, camera = "phoxi_s", views = None, distance_m = None, stable_pose = 0, physics = true, backend = "auto", depth_from = "rendered"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_mesh<'py>(
    py: Python<'py>,
    vertices: Bound<'py, PyAny>,
    triangles: Bound<'py, PyAny>,
    model: Option<&str>,
    fuse: bool,
    cem: bool,
    hand_check: bool,
    seed: u64,
    camera: &str,
    views: Option<usize>,
    distance_m: Option<f32>,
    stable_pose: usize,
    physics: bool,
    backend: &str,
    depth_from: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let mesh = mesh_of(&vertices, &triangles)?;
    let depth_from = match depth_from {
        "rendered" => None,
        other => Some(
            other
                .parse::<DepthFrom>()
                .map_err(|e| PyValueError::new_err(format!("depth_from: {e}, or rendered")))?,
        ),
    };
    let options = PlanOptions {
        camera: camera.parse().map_err(camera_error)?,
        views,
        distance_m,
        stable_pose,
        physics,
        depth_from,
        ..options(fuse, cem, hand_check, seed)
    };
    let backend = backend_of(backend)?;
    let source = options.chance_source(model.unwrap_or(options.default_model()), false);
    let net = network(model, &options)?;
    let (policy, params) = options.on_mesh(net).map_err(pipeline_error)?;
    let report = py
        .detach(|| -> mvgrasp::Result<_> {
            let renderer = renderer(backend)?;
            Ok(plan_grasp(&renderer, &mesh, &policy, &params)?)
        })
        .map_err(pipeline_error)?;
    let file = GraspsFile::of_rendered(&report);
    let t = report.timings;
    let timings = serde_json::json!({
        "render_s": t.render_s, "depth_s": t.depth_s, "fuse_s": t.fuse_s, "plan_s": t.plan_s, "check_s": t.check_s,
    });
    let hold_probability = match (report.best.as_ref(), source) {
        (Some(best), Some(source)) => source.of(best).map_err(pipeline_error)?,
        _ => None,
    };
    let result = to_python(
        py,
        &serde_json::json!({"report": report, "timings": timings, "hold_probability": hold_probability}),
    )?;
    result.set_item("grasps_json", file.to_json().map_err(pipeline_error)?)?;
    Ok(result)
}

/// The RGB views of `plan_rgb` and `predict_depth`: per view an `(H, W, 3)` uint8 image, its
/// 3x3 camera matrix, its pose and optionally its mask; at least `min_views` views (planning
/// asks for two, the LSM's prediction takes one).
fn rgb_views(
    images: &[Bound<'_, PyAny>],
    ks: &[Bound<'_, PyAny>],
    world_from_cameras: &[Bound<'_, PyAny>],
    masks: Option<&Vec<Option<Bound<'_, PyAny>>>>,
    min_views: usize,
) -> PyResult<Vec<RgbView>> {
    let n = images.len();
    let mut lengths = vec![n, ks.len(), world_from_cameras.len()];
    lengths.extend(masks.map(Vec::len));
    one_per_view(
        "images, ks, world_from_cameras (and masks)",
        &lengths,
        min_views,
    )?;
    let mut views = Vec::with_capacity(n);
    for i in 0..n {
        let name = format!("images[{i}]");
        let image = array_of::<u8>(&name, &images[i])?;
        let image = image.as_array();
        let [h, w, 3] = *image.shape() else {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {:?}, expected (H, W, 3)",
                image.shape()
            )));
        };
        let (w, h) = image_size(&name, image.shape(), h, w)?;
        let camera = Camera {
            intrinsics: intrinsics_of(&format!("ks[{i}]"), &ks[i], &name, w, h)?,
            world_from_camera: pose_of(
                &format!("world_from_cameras[{i}]"),
                &world_from_cameras[i],
            )?,
        };
        let rgb = image
            .rows()
            .into_iter()
            .map(|p| [p[0], p[1], p[2]])
            .collect();
        let mask = match masks.and_then(|m| m[i].as_ref()) {
            Some(m) => Some(mask_of(&format!("masks[{i}]"), m, w, h)?),
            None => None,
        };
        views.push(RgbView { camera, rgb, mask });
    }
    Ok(views)
}

/// Plans a grasp on RGB views, as `plan --rgb` does: the views' depth predicted by the
/// plane-sweep baseline (`depth_from="baseline"`, the default), the sweep refined by the
/// shipped network (`"refined"`), the shipped multi-view stereo network (`"mvs"`) or the
/// shipped Learnt Stereo Machine (`"lsm"`), then the multi-view planner. `images`: per view an `(H, W, 3)` uint8 image;
/// `ks`, `world_from_cameras`: their cameras, posed in the table frame (z up, the table at
/// z = 0); `masks`: per view the object's pixels or `None`. Returns `grasps.json`'s content
/// (with `as_json`, its text).
#[pyfunction]
#[pyo3(signature = (images, ks, world_from_cameras, *, masks = None, model = None, depth_from = "baseline", cem = false, hand_check = true, seed = 0, as_json = false))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn plan_rgb<'py>(
    py: Python<'py>,
    images: Vec<Bound<'py, PyAny>>,
    ks: Vec<Bound<'py, PyAny>>,
    world_from_cameras: Vec<Bound<'py, PyAny>>,
    masks: Option<Vec<Option<Bound<'py, PyAny>>>>,
    model: Option<&str>,
    depth_from: &str,
    cem: bool,
    hand_check: bool,
    seed: u64,
    as_json: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let predictor = predictor_of(depth_from)?;
    let views = rgb_views(&images, &ks, &world_from_cameras, masks.as_ref(), 2)?;
    let options = options(true, cem, hand_check, seed);
    let net = network(model, &options)?;
    let file = py.detach(|| -> mvgrasp::Result<GraspsFile> {
        let (policy, gripper, params) = options.on_depth(net)?;
        let report = plan_on_rgb_views(&policy, &gripper, &views, &params, &predictor)?;
        Ok(GraspsFile::of_views(&report.plan))
    });
    grasps_output(py, &file.map_err(pipeline_error)?, as_json)
}

/// Each RGB view's depth predicted from all of them (`depth_from="baseline"`, the default:
/// silhouette carving and a plane sweep, `mvgrasp::stereo`; `"refined"`: the sweep refined by
/// the shipped network, `mvgrasp::sweep_refiner`; `"mvs"`: the shipped multi-view stereo
/// network; `"lsm"`: the shipped Learnt Stereo Machine), as
/// `plan --rgb` predicts it: a `(V, H, W)`
/// float32 array, metres along each optical axis, 0 where unknown. The inputs are
/// `plan_rgb`'s; the LSM also takes a single view (the baseline and the MVS network need two).
#[pyfunction]
#[pyo3(signature = (images, ks, world_from_cameras, *, masks = None, depth_from = "baseline"))]
pub(crate) fn predict_depth<'py>(
    py: Python<'py>,
    images: Vec<Bound<'py, PyAny>>,
    ks: Vec<Bound<'py, PyAny>>,
    world_from_cameras: Vec<Bound<'py, PyAny>>,
    masks: Option<Vec<Option<Bound<'py, PyAny>>>>,
    depth_from: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let predictor = predictor_of(depth_from)?;
    let views = rgb_views(&images, &ks, &world_from_cameras, masks.as_ref(), 1)?;
    let (w, h) = (
        views[0].camera.intrinsics.width as usize,
        views[0].camera.intrinsics.height as usize,
    );
    if views.iter().any(|v| {
        (
            v.camera.intrinsics.width as usize,
            v.camera.intrinsics.height as usize,
        ) != (w, h)
    }) {
        return Err(PyValueError::new_err(
            "images: views of different sizes (one array holds them all)",
        ));
    }
    let depths = py
        .detach(|| predictor.depths(&views))
        .map_err(pipeline_error)?;
    let values: Vec<f32> = depths.into_iter().flatten().collect();
    Ok(PyArray1::from_vec(py, values)
        .reshape([views.len(), h, w])?
        .into_any())
}

/// The shipped depth predictor a `depth_from` argument names.
fn predictor_of(depth_from: &str) -> PyResult<DepthPredictor> {
    let from: DepthFrom = depth_from
        .parse()
        .map_err(|e| PyValueError::new_err(format!("depth_from: {e}")))?;
    DepthPredictor::shipped(from).map_err(pipeline_error)
}
