//! Networks: GQ-CNN exports loaded as the planner loads them, and scoring of NumPy batches.

use std::path::{Path, PathBuf};

use mvgrasp::planner::models;
use mvgrasp_infer::{Gqcnn, GqcnnWorkspace, Tensor};
use numpy::{PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::arrays::array_of;
use crate::convert::to_python;
use crate::errors::WeightsError;

/// The network `model` names: a shipped one (`gqcnn_small_topdown`, `gqcnn_small_multiview`)
/// or an export's `NAME.json`.
pub(crate) fn load_model(model: &str) -> PyResult<Gqcnn> {
    match models::shipped(model) {
        Some(shipped) => shipped.load().map_err(|e| e.to_string()),
        None => Gqcnn::load(Path::new(model)).map_err(|e| e.to_string()),
    }
    .map_err(|e| WeightsError::new_err(format!("{model}: {e}")))
}

/// Loads a GQ-CNN export (`NAME.json` and the `NAME.safetensors` it names) as the planner
/// does, checking every tensor's name and shape and the input contract against the
/// architecture; its description as a dict (format, architecture, normalisation, `input`, the
/// training record). Raises `mvgrasp.WeightsError` naming the file and what is wrong.
#[pyfunction]
pub(crate) fn load_network(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let net = py
        .detach(|| Gqcnn::load(&path))
        .map_err(|e| WeightsError::new_err(e.to_string()))?;
    to_python(py, net.description())
}

/// Scores a batch of grasp crops with a GQ-CNN, as the planner scores its candidates.
///
/// `model`: a shipped network's name or an export's `NAME.json`. `depth`: float32 crops, `(N,
/// S, S)` or `(N, 1, S, S)` with the network's crop side `S` (metres, already cut and scaled
/// to the network's input contract). `pose`: float32 `(N, P)` with the network's pose inputs
/// (the grasp depth, and theta for a multi-view GQ-CNN), or `(N,)` when `P` is 1. Returns the
/// probability that each grasp is robust, `(N,)` float32, or with `logits` the two logits (not
/// robust, robust), `(N, 2)`. The GIL is released while scoring.
#[pyfunction]
#[pyo3(signature = (model, depth, pose, *, logits = false))]
pub(crate) fn score_crops<'py>(
    py: Python<'py>,
    model: &str,
    depth: Bound<'py, PyAny>,
    pose: Bound<'py, PyAny>,
    logits: bool,
) -> PyResult<Bound<'py, PyAny>> {
    let net = load_model(model)?;
    let arch = net.architecture();
    let (s, p) = (arch.image_size_px, arch.pose_inputs);
    let (depth, pose) = (
        array_of::<f32>("depth", &depth)?,
        array_of::<f32>("pose", &pose)?,
    );
    let d = depth.as_array();
    let n = d.shape().first().copied().unwrap_or(0);
    if d.shape() != [n, s, s] && d.shape() != [n, 1, s, s] {
        return Err(PyValueError::new_err(format!(
            "depth: shape {:?}, expected (N, {s}, {s}) or (N, 1, {s}, {s}) for {model}",
            d.shape()
        )));
    }
    let q = pose.as_array();
    if q.shape() != [n, p] && !(p == 1 && q.shape() == [n]) {
        return Err(PyValueError::new_err(format!(
            "pose: shape {:?}, expected ({n}, {p}){} for {model} (one row per crop of depth)",
            q.shape(),
            if p == 1 {
                format!(" or ({n},)")
            } else {
                String::new()
            }
        )));
    }
    let to_error = |e: mvgrasp_infer::InferError| PyValueError::new_err(e.to_string());
    let depth = Tensor::new(&[n, 1, s, s], d.iter().copied().collect()).map_err(to_error)?;
    let pose = Tensor::new(&[n, p], q.iter().copied().collect()).map_err(to_error)?;
    let scores = py
        .detach(|| {
            let mut workspace = GqcnnWorkspace::default();
            if logits {
                net.logits(&depth, &pose, &mut workspace)
                    .map(|t| t.data().to_vec())
            } else {
                net.predict(&depth, &pose, &mut workspace)
            }
        })
        .map_err(to_error)?;
    let array = PyArray1::from_vec(py, scores);
    Ok(if logits {
        array.reshape([n, 2])?.into_any()
    } else {
        array.into_any()
    })
}
