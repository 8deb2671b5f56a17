//! The Python exception tree and the mapping from Rust errors onto it.
//!
//! ```text
//! Exception
//! └── mvgrasp.MvGraspError
//!     ├── mvgrasp.MeshError      a mesh file cannot be loaded or is not a usable mesh
//!     ├── mvgrasp.CameraError    bad intrinsics or extrinsics
//!     └── mvgrasp.WeightsError   a network's weights are missing or do not match
//! ```
//!
//! The message is always the Rust error's `Display` text, which names the file and the fault.
//! A bad argument value (not a bad file) raises Python's own `ValueError`.

use mvgrasp_geometry::GeometryError;
use pyo3::PyErr;
use pyo3::create_exception;
use pyo3::exceptions::{PyException, PyValueError};

create_exception!(
    mvgrasp,
    MvGraspError,
    PyException,
    "The base class of every error that mvgrasp raises."
);
create_exception!(
    mvgrasp,
    MeshError,
    MvGraspError,
    "A mesh file cannot be loaded or is not a usable mesh; the message names the file."
);
create_exception!(
    mvgrasp,
    CameraError,
    MvGraspError,
    "Camera intrinsics or extrinsics are missing or invalid."
);
create_exception!(
    mvgrasp,
    WeightsError,
    MvGraspError,
    "A network's weights are missing, unreadable or do not match its architecture."
);

/// Maps an error from loading a mesh: a bad argument is a `ValueError`, anything about the file
/// is a `MeshError`.
pub(crate) fn mesh_error(error: GeometryError) -> PyErr {
    match error {
        GeometryError::InvalidParameter { .. } => PyValueError::new_err(error.to_string()),
        _ => MeshError::new_err(error.to_string()),
    }
}

/// Maps a pipeline error: meshes are `MeshError`, cameras `CameraError`, the rest
/// `MvGraspError`; always with the Rust message.
pub(crate) fn pipeline_error(error: mvgrasp::Error) -> PyErr {
    match error {
        mvgrasp::Error::Geometry(e) => mesh_error(e),
        other => MvGraspError::new_err(other.to_string()),
    }
}
