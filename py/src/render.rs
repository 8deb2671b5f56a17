//! Rendering: RGB, depth and mask of a mesh on the table for a batch of cameras, as NumPy
//! arrays, with the renderer the CLI's `render` uses (one per backend, kept for the process).

use std::sync::{Arc, Mutex, PoisonError};

use mvgrasp::convert::render_view;
use mvgrasp::dataset::{DatasetConfig, write_dataset};
use mvgrasp::render::{Backend, Colors, Renderer};
use mvgrasp::scene::{SceneData, TABLE_HALF_SIDE_M};
use mvgrasp_geometry::{Camera, Intrinsics, IntrinsicsPreset, Pose3};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::arrays::{array_of, intrinsics_of, mesh_of, optional_pose, pose_of};
use crate::errors::{RenderError, camera_error, dataset_error};
use crate::grasp_dataset::library_sources;

/// The graphics backend a `backend` argument names; `ValueError` for another name.
pub(crate) fn backend_of(backend: &str) -> PyResult<Backend> {
    Backend::parse(backend).ok_or_else(|| {
        PyValueError::new_err(format!(
            "backend: {backend:?}, expected auto, vulkan, gl, metal or dx12"
        ))
    })
}

/// The renderers opened so far, one per backend asked for.
static RENDERERS: Mutex<Vec<(Backend, Arc<Renderer>)>> = Mutex::new(Vec::new());

/// The renderer of `backend`, opened on first use.
pub(crate) fn renderer(backend: Backend) -> Result<Arc<Renderer>, mvgrasp::render::RenderError> {
    let mut renderers = RENDERERS.lock().unwrap_or_else(PoisonError::into_inner);
    if let Some((_, r)) = renderers.iter().find(|(b, _)| *b == backend) {
        return Ok(Arc::clone(r));
    }
    let r = Arc::new(Renderer::new(backend)?);
    renderers.push((backend, Arc::clone(&r)));
    Ok(r)
}

/// `n` random 8-bit RGB colours from `seed`, as an `(n, 3)` uint8 array: the colours the
/// datasets give a mesh (per vertex or per triangle, from the seeds in `object.json`).
#[pyfunction]
pub(crate) fn random_colors(py: Python<'_>, seed: u64, n: usize) -> PyResult<Bound<'_, PyAny>> {
    let flat: Vec<u8> = mvgrasp::render::random_colors(seed, n)
        .into_iter()
        .flatten()
        .collect();
    Ok(PyArray1::from_vec(py, flat).reshape([n, 3])?.into_any())
}

/// Renders a mesh for a batch of cameras, as the CLI's `render` does; a dict of `rgb`
/// `(V, H, W, 3)` uint8, `depth` `(V, H, W)` float32 (z along the optical axis, metres; 0 where
/// nothing was drawn) and `mask` `(V, H, W)` uint8 (0 background, 1 object, 2 table).
///
/// `vertices`, `triangles`: the mesh (any real and integer dtypes). `ks`, `world_from_cameras`:
/// per view a 3x3 camera matrix and a 4x4 pose (OpenCV frame), all `width` x `height` pixels.
/// `world_from_object`: where the mesh is (default: where it is). `colors`: uint8 `(N, 3)` per
/// vertex, or `(M, 3)` per triangle with `per_face`; default one grey. `table`: the datasets'
/// 0.8 m grey square at z = 0. `backend`: `auto`, `vulkan` or `gl` (see `MVGRASP_RENDER_BACKEND`).
/// The GIL is released while rendering. Raises `ValueError` for bad arrays (named) and
/// `mvgrasp.RenderError` when no graphics adapter opens.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, ks, world_from_cameras, *, width, height, world_from_object = None, colors = None, per_face = false, table = true, backend = "auto"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn render<'py>(
    py: Python<'py>,
    vertices: Bound<'py, PyAny>,
    triangles: Bound<'py, PyAny>,
    ks: Vec<Bound<'py, PyAny>>,
    world_from_cameras: Vec<Bound<'py, PyAny>>,
    width: u32,
    height: u32,
    world_from_object: Option<Bound<'py, PyAny>>,
    colors: Option<Bound<'py, PyAny>>,
    per_face: bool,
    table: bool,
    backend: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = mesh_of(&vertices, &triangles)?;
    let backend = backend_of(backend)?;
    if ks.len() != world_from_cameras.len() {
        return Err(PyValueError::new_err(format!(
            "ks and world_from_cameras: one per view, got {} and {}",
            ks.len(),
            world_from_cameras.len()
        )));
    }
    let mut cameras = Vec::with_capacity(ks.len());
    for (i, (k, pose)) in ks.iter().zip(&world_from_cameras).enumerate() {
        cameras.push(Camera {
            intrinsics: intrinsics_of(&format!("ks[{i}]"), k, "width x height", width, height)?,
            world_from_camera: pose_of(&format!("world_from_cameras[{i}]"), pose)?,
        });
    }
    let pose =
        optional_pose("world_from_object", world_from_object.as_ref())?.unwrap_or(Pose3::IDENTITY);
    let colors: Option<Vec<[u8; 3]>> = match colors {
        None => None,
        Some(c) => {
            let c = array_of::<u8>("colors", &c)?;
            let c = c.as_array();
            let (what, expected, flag) = if per_face {
                ("triangle", mesh.triangles().len(), "True")
            } else {
                ("vertex", mesh.vertices().len(), "False")
            };
            if c.shape() != [expected, 3] {
                return Err(PyValueError::new_err(format!(
                    "colors: shape {:?}, expected ({expected}, 3): one per {what} of the mesh \
                     (per_face={flag})",
                    c.shape()
                )));
            }
            Some(c.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
        }
    };

    let frames = py
        .detach(|| -> Result<_, mvgrasp::render::RenderError> {
            let renderer = renderer(backend)?;
            let data = SceneData::of_mesh(&mesh, &pose, TABLE_HALF_SIDE_M);
            let colors = match &colors {
                None => Colors::Uniform([200, 200, 200]),
                Some(c) if per_face => Colors::PerFace(c),
                Some(c) => Colors::PerVertex(c),
            };
            let scene = renderer.upload(&data.mesh_inputs(mesh.triangles(), colors, table))?;
            let views: Vec<_> = cameras.iter().map(render_view).collect();
            renderer.render(&scene, &views)
        })
        .map_err(|e| RenderError::new_err(e.to_string()))?;

    let (v, h, w) = (frames.len(), height as usize, width as usize);
    let mut rgb = Vec::with_capacity(v * h * w * 3);
    let mut depth = Vec::with_capacity(v * h * w);
    let mut mask = Vec::with_capacity(v * h * w);
    for frame in frames {
        rgb.extend_from_slice(&frame.rgb);
        depth.extend_from_slice(&frame.depth_m);
        mask.extend_from_slice(&frame.mask);
    }
    let dict = PyDict::new(py);
    dict.set_item("rgb", PyArray1::from_vec(py, rgb).reshape([v, h, w, 3])?)?;
    dict.set_item("depth", PyArray1::from_vec(py, depth).reshape([v, h, w])?)?;
    dict.set_item("mask", PyArray1::from_vec(py, mask).reshape([v, h, w])?)?;
    Ok(dict)
}

/// Renders the multi-view RGB-D dataset into `out`, as the CLI's `render` does (the same files,
/// byte for byte): per object its training and novel test views (RGB, depth, masks, cameras),
/// finished objects skipped on a rerun. The objects are mesh files or folders (`meshes`), or
/// the built-in library (`per_category` of each of `categories`, default all); `seed` seeds
/// the camera layouts and colours, `camera` is an intrinsics preset, `table` the table plane.
/// Returns `{"written", "skipped", "views"}`. The GIL is released while it runs.
#[pyfunction]
#[pyo3(signature = (out, *, meshes = None, per_category = 1, categories = None, library_seed = 0, seed = 0, camera = "phoxi_s", table = true, backend = "auto"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn generate_rgbd_dataset<'py>(
    py: Python<'py>,
    out: std::path::PathBuf,
    meshes: Option<Vec<std::path::PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
    seed: u64,
    camera: &str,
    table: bool,
    backend: &str,
) -> PyResult<Bound<'py, PyDict>> {
    let preset: IntrinsicsPreset = camera.parse().map_err(camera_error)?;
    let backend = backend_of(backend)?;
    let sources = library_sources(meshes, per_category, categories, library_seed)?;
    let config = DatasetConfig {
        seed,
        intrinsics: Intrinsics::preset(preset),
        table,
        ..Default::default()
    };
    let summary = py.detach(|| -> mvgrasp::Result<_> {
        let renderer = renderer(backend)?;
        write_dataset(&renderer, &sources, &config, &out, false)
    });
    let summary = summary.map_err(dataset_error)?;
    let dict = PyDict::new(py);
    dict.set_item("written", summary.written)?;
    dict.set_item("skipped", summary.skipped)?;
    dict.set_item("views", summary.views)?;
    Ok(dict)
}

/// One folder of an RGB-D dataset (`render`'s `OBJECT/train` or `OBJECT/test`, or any folder
/// of that layout) read back through the Rust readers `plan --rgb` and `plan --views-dir` use:
/// a dict of `rgb` (V, H, W, 3) uint8, `depth` (V, H, W) float32 metres (0: nothing), `mask`
/// (V, H, W) bool (the object's pixels; `None` without masks), `k` (V, 3, 3) and
/// `world_from_camera` (V, 4, 4) float64. Raises `mvgrasp.DatasetError` naming the file.
#[pyfunction]
pub(crate) fn read_rgbd_folder(
    py: Python<'_>,
    dir: std::path::PathBuf,
) -> PyResult<Bound<'_, PyDict>> {
    let (rgb, depth) = py
        .detach(|| -> mvgrasp::Result<_> {
            Ok((
                mvgrasp::planner::read_rgb_dir(&dir)?,
                mvgrasp::planner::read_views_dir(&dir)?,
            ))
        })
        // Whatever the reader's kind of error (a file of the folder): the dataset's.
        .map_err(|e| crate::errors::DatasetError::new_err(e.to_string()))?;
    let (v, first) = (rgb.len(), &rgb[0].camera.intrinsics);
    let (w, h) = (first.width as usize, first.height as usize);
    if rgb.iter().any(|view| {
        (view.camera.intrinsics.width, view.camera.intrinsics.height) != (first.width, first.height)
    }) {
        return Err(crate::errors::DatasetError::new_err(format!(
            "{}: the views are not all {w} x {h} pixels",
            dir.display()
        )));
    }
    let out = PyDict::new(py);
    let pixels: Vec<u8> = rgb
        .iter()
        .flat_map(|view| view.rgb.iter().flatten().copied())
        .collect();
    out.set_item("rgb", PyArray1::from_vec(py, pixels).reshape([v, h, w, 3])?)?;
    let values: Vec<f32> = depth
        .iter()
        .flat_map(|view| view.depth.as_slice().iter().copied())
        .collect();
    out.set_item("depth", PyArray1::from_vec(py, values).reshape([v, h, w])?)?;
    if rgb.iter().all(|view| view.mask.is_some()) {
        let masks: Vec<bool> = rgb
            .iter()
            .flat_map(|view| view.mask.iter().flatten().copied())
            .collect();
        out.set_item("mask", PyArray1::from_vec(py, masks).reshape([v, h, w])?)?;
    } else {
        out.set_item("mask", py.None())?;
    }
    let ks: Vec<Bound<'_, PyArray2<f64>>> = rgb
        .iter()
        .map(|view| crate::arrays::k_array(py, &view.camera.intrinsics))
        .collect();
    let poses: Vec<Bound<'_, PyArray2<f64>>> = rgb
        .iter()
        .map(|view| crate::arrays::pose_array(py, &view.camera.world_from_camera))
        .collect();
    let numpy = py.import("numpy")?;
    out.set_item("k", numpy.call_method1("stack", (ks,))?)?;
    out.set_item("world_from_camera", numpy.call_method1("stack", (poses,))?)?;
    Ok(out)
}
