//! The Python exception tree and the mapping from Rust errors onto it.
//!
//! ```text
//! Exception
//! └── mvgrasp.MvGraspError
//!     ├── mvgrasp.MeshError      a mesh file cannot be loaded or is not a usable mesh
//!     ├── mvgrasp.CameraError    bad intrinsics or extrinsics
//!     ├── mvgrasp.WeightsError   a network's weights are missing or do not match
//!     ├── mvgrasp.RenderError    no graphics adapter, or rendering failed
//!     ├── mvgrasp.PlanningError  depth images, views or a network the planner cannot use
//!     ├── mvgrasp.GraspError     a gripper file the grasp analysis cannot use
//!     └── mvgrasp.DatasetError   a dataset's config, folder, shards or manifest
//! ```
//!
//! The Rust error's variant decides the class (`pipeline_error`); the message is always its
//! `Display` text, which names the file and the fault. A bad argument value (not a bad file)
//! raises Python's own `ValueError`.

use mvgrasp::grasp::GraspError as RustGraspError;
use mvgrasp::{Error, ErrorKind, RuntimeError};
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

create_exception!(
    mvgrasp,
    RenderError,
    MvGraspError,
    "No graphics adapter could be opened, or rendering failed."
);
create_exception!(
    mvgrasp,
    PlanningError,
    MvGraspError,
    "Depth images, views or a network that the planner cannot use."
);
create_exception!(
    mvgrasp,
    GraspError,
    MvGraspError,
    "A gripper file (or an object) that the grasp analysis cannot use; the message names the file."
);
create_exception!(
    mvgrasp,
    DatasetError,
    MvGraspError,
    "A dataset's config, folder, shards or manifest cannot be used; the message names the file."
);

/// Maps an error from loading a mesh: a bad argument is a `ValueError`, anything about the file
/// is a `MeshError`.
pub(crate) fn mesh_error(error: GeometryError) -> PyErr {
    match error {
        GeometryError::InvalidParameter { .. } => PyValueError::new_err(error.to_string()),
        _ => MeshError::new_err(error.to_string()),
    }
}

/// Maps an error from a camera file: `CameraError`, with the Rust message naming the file.
pub(crate) fn camera_error(error: GeometryError) -> PyErr {
    CameraError::new_err(error.to_string())
}

/// Maps an error of the grasp analysis: a bad argument value is a `ValueError`, a gripper file
/// or an object it cannot use a `GraspError`.
pub(crate) fn grasp_error(error: RustGraspError) -> PyErr {
    match error {
        RustGraspError::InvalidParameter { .. } => PyValueError::new_err(error.to_string()),
        _ => GraspError::new_err(error.to_string()),
    }
}

/// Maps an error of a dataset function: as [`pipeline_error`], except that a file that cannot
/// be read or written is a `DatasetError` too.
pub(crate) fn dataset_error(error: impl Into<Error>) -> PyErr {
    let error = error.into();
    match error.kind() {
        ErrorKind::Io => DatasetError::new_err(error.to_string()),
        _ => pipeline_error(error),
    }
}

/// Maps a pipeline error onto the tree by the Rust error's kind ([`Error::kind`]), always with
/// its message; a geometry error as [`mesh_error`] does.
pub(crate) fn pipeline_error(error: impl Into<Error>) -> PyErr {
    let error = error.into();
    let message = error.to_string();
    match (error.kind(), error) {
        (_, Error::Runtime(RuntimeError::Geometry(e))) => mesh_error(e),
        (_, Error::Runtime(RuntimeError::Grasp(e))) => grasp_error(e),
        (_, Error::Runtime(RuntimeError::PlanOption { .. })) => PyValueError::new_err(message),
        (ErrorKind::Rendering, _) => RenderError::new_err(message),
        (ErrorKind::Weights, _) => WeightsError::new_err(message),
        (ErrorKind::Planning, _) => PlanningError::new_err(message),
        (ErrorKind::Dataset, _) => DatasetError::new_err(message),
        (ErrorKind::Grasp, _) => GraspError::new_err(message),
        (ErrorKind::Geometry | ErrorKind::Io, _) => MvGraspError::new_err(message),
    }
}
