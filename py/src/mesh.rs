//! Meshes: files to NumPy arrays.

use std::path::PathBuf;

use mvgrasp_geometry::{LoadOptions, load_mesh_with};
use pyo3::prelude::*;

use crate::arrays::{MeshArrays, mesh_arrays};
use crate::errors::mesh_error;

/// Loads an OBJ, STL or URDF file as `(vertices, triangles)`.
///
/// `vertices` is an `(N, 3)` float32 array in metres (file coordinates times `scale`),
/// `triangles` an `(M, 3)` uint32 array of vertex indices. Raises `mvgrasp.MeshError` naming the
/// file when it is missing, unparsable, has NaN/inf vertices or an implausible size, and
/// `ValueError` when `scale` is not a finite number > 0. The GIL is released while loading.
#[pyfunction]
#[pyo3(signature = (path, scale = 1.0))]
pub(crate) fn load_mesh(py: Python<'_>, path: PathBuf, scale: f32) -> PyResult<MeshArrays<'_>> {
    let options = LoadOptions {
        scale,
        ..LoadOptions::default()
    };
    let mesh = py
        .detach(|| load_mesh_with(&path, &options))
        .map_err(mesh_error)?;

    mesh_arrays(py, &mesh)
}
