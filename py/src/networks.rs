//! Networks: a GQ-CNN export loaded as the planner loads it.

use std::path::PathBuf;

use mvgrasp_infer::Gqcnn;
use pyo3::prelude::*;

use crate::convert::to_python;
use crate::errors::WeightsError;

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
