//! Cameras: intrinsics files to Python.

use std::path::PathBuf;

use mvgrasp_geometry::Intrinsics;
use pyo3::prelude::*;

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
