//! Meshes: files to NumPy arrays.

use std::path::PathBuf;

use mvgrasp_geometry::{LoadOptions, load_mesh_with};
use numpy::{PyArray1, PyArray2, PyArrayMethods};
use pyo3::prelude::*;

use crate::errors::mesh_error;

/// The vertices and triangles of a mesh, as NumPy arrays.
type MeshArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<u32>>);

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

    let vertices: Vec<f32> = mesh
        .vertices()
        .iter()
        .flat_map(|v| [v.x, v.y, v.z])
        .collect();
    let triangles: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
    let vertices = PyArray1::from_vec(py, vertices).reshape([mesh.vertices().len(), 3])?;
    let triangles = PyArray1::from_vec(py, triangles).reshape([mesh.triangles().len(), 3])?;
    Ok((vertices, triangles))
}
