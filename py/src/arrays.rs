//! NumPy arrays to Rust values and back: meshes, camera matrices, poses. Every error names the
//! argument and what was expected.

use mvgrasp_geometry::{Intrinsics, Pose3, TriangleMesh, Vec3, pose_as_matrix};
use numpy::ndarray::Array2;
use numpy::{AllowTypeChange, IntoPyArray, PyArray1, PyArray2, PyArrayLike2, PyArrayMethods};
use numpy::{PyReadonlyArray2, PyReadonlyArrayDyn};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

use crate::errors::mesh_error;

/// The vertices and triangles of a mesh, as NumPy arrays.
pub(crate) type MeshArrays<'py> = (Bound<'py, PyArray2<f32>>, Bound<'py, PyArray2<u32>>);

/// A mesh's `(N, 3)` float32 vertices and `(M, 3)` uint32 triangles.
pub(crate) fn mesh_arrays<'py>(py: Python<'py>, mesh: &TriangleMesh) -> PyResult<MeshArrays<'py>> {
    let vertices: Vec<f32> = mesh.vertices().iter().flat_map(|v| v.to_array()).collect();
    let triangles: Vec<u32> = mesh.triangles().iter().flatten().copied().collect();
    let vertices = PyArray1::from_vec(py, vertices).reshape([mesh.vertices().len(), 3])?;
    let triangles = PyArray1::from_vec(py, triangles).reshape([mesh.triangles().len(), 3])?;
    Ok((vertices, triangles))
}

/// A mesh from `(N, 3)` vertices (metres, any real dtype: converted to float32) and `(M, 3)`
/// triangles (any integer dtype), checked as a mesh file is: indices in range, finite
/// vertices, zero-area triangles dropped. A `trimesh.Trimesh`'s `vertices` and `faces` go in
/// as they are.
pub(crate) fn mesh_of(
    vertices: &PyArrayLike2<'_, f32, AllowTypeChange>,
    triangles: &PyArrayLike2<'_, i64, AllowTypeChange>,
) -> PyResult<TriangleMesh> {
    let v = vertices.as_array();
    if v.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "vertices: shape {:?}, expected (N, 3)",
            v.shape()
        )));
    }
    let t = triangles.as_array();
    if t.ncols() != 3 {
        return Err(PyValueError::new_err(format!(
            "triangles: shape {:?}, expected (M, 3)",
            t.shape()
        )));
    }
    let vertices: Vec<Vec3> = v
        .rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect();
    let mut tris = Vec::with_capacity(t.nrows());
    for (i, row) in t.rows().into_iter().enumerate() {
        let mut tri = [0u32; 3];
        for (k, &index) in row.iter().enumerate() {
            tri[k] = u32::try_from(index).map_err(|_| {
                PyValueError::new_err(format!(
                    "triangles[{i}]: index {index} is not a vertex index (0 to {})",
                    vertices.len().saturating_sub(1)
                ))
            })?;
        }
        tris.push(tri);
    }
    TriangleMesh::new(vertices, tris).map_err(mesh_error)
}

/// A depth image's size and values: (H, W) or (H, W, 1) float32 metres; `name` names the
/// argument in errors.
pub(crate) fn depth_of(
    name: &str,
    depth: &PyReadonlyArrayDyn<'_, f32>,
) -> PyResult<(u32, u32, Vec<f32>)> {
    let shape = depth.as_array().shape().to_vec();
    let (height, width) = match shape[..] {
        [h, w] | [h, w, 1] => (h, w),
        _ => {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {shape:?}, expected (H, W) or (H, W, 1)"
            )));
        }
    };
    let size =
        |n: usize| u32::try_from(n).map_err(|e| PyValueError::new_err(format!("{name}: {e}")));
    Ok((
        size(width)?,
        size(height)?,
        depth.as_array().iter().copied().collect(),
    ))
}

/// The intrinsics of a 3x3 camera matrix without skew, for a `width` x `height` image.
pub(crate) fn intrinsics_of(
    name: &str,
    k: &PyReadonlyArray2<'_, f64>,
    width: u32,
    height: u32,
) -> PyResult<Intrinsics> {
    let k = k.as_array();
    if k.shape() != [3, 3] {
        return Err(PyValueError::new_err(format!(
            "{name}: shape {:?}, expected (3, 3)",
            k.shape()
        )));
    }
    if k[[0, 1]] != 0.0 || k[[1, 0]] != 0.0 || [k[[2, 0]], k[[2, 1]], k[[2, 2]]] != [0.0, 0.0, 1.0]
    {
        return Err(PyValueError::new_err(format!(
            "{name}: expected [[fx, 0, cx], [0, fy, cy], [0, 0, 1]] (no skew)"
        )));
    }
    Intrinsics::new(
        k[[0, 0]] as f32,
        k[[1, 1]] as f32,
        k[[0, 2]] as f32,
        k[[1, 2]] as f32,
        width,
        height,
        0.1,
        2.0,
    )
    .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
}

/// The 3x3 camera matrix of `intrinsics`.
pub(crate) fn k_array<'py>(py: Python<'py>, k: &Intrinsics) -> Bound<'py, PyArray2<f64>> {
    let (fx, fy, cx, cy) = (
        f64::from(k.fx),
        f64::from(k.fy),
        f64::from(k.cx),
        f64::from(k.cy),
    );
    let rows = [[fx, 0.0, cx], [0.0, fy, cy], [0.0, 0.0, 1.0]];
    Array2::from_shape_fn((3, 3), |(i, j)| rows[i][j]).into_pyarray(py)
}

/// A rigid 4x4 pose (rows).
pub(crate) fn pose_of(name: &str, pose: &PyReadonlyArray2<'_, f64>) -> PyResult<Pose3> {
    let p = pose.as_array();
    if p.shape() != [4, 4] {
        return Err(PyValueError::new_err(format!(
            "{name}: shape {:?}, expected (4, 4)",
            p.shape()
        )));
    }
    // Through f32, as a JSON file's pose is read: the same values give the same bits.
    let rows = std::array::from_fn(|i| std::array::from_fn(|j| p[[i, j]] as f32));
    pose_as_matrix::from_rows(rows).map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
}

/// A pose as a float64 4x4 array (rows).
pub(crate) fn pose_array<'py>(py: Python<'py>, pose: &Pose3) -> Bound<'py, PyArray2<f64>> {
    let m = pose.to_mat4();
    let cols = m.to_cols_array_2d();
    Array2::from_shape_fn((4, 4), |(i, j)| f64::from(cols[j][i])).into_pyarray(py)
}

/// A float32 3-vector as a `(3,)` float64 array.
pub(crate) fn vec3_array<'py>(py: Python<'py>, v: Vec3) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v.to_array().map(f64::from).to_vec())
}

/// One rigid 4x4 pose `(4, 4)` or a batch `(N, 4, 4)` (rows), as a list.
pub(crate) fn poses_of(name: &str, poses: &PyReadonlyArrayDyn<'_, f64>) -> PyResult<Vec<Pose3>> {
    let p = poses.as_array();
    let batch = match p.shape() {
        [4, 4] => 1,
        [n, 4, 4] => *n,
        shape => {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {shape:?}, expected (4, 4) or (N, 4, 4)"
            )));
        }
    };
    let values: Vec<f64> = p.iter().copied().collect();
    (0..batch)
        .map(|i| {
            let m = &values[16 * i..16 * i + 16];
            let rows = std::array::from_fn(|r| std::array::from_fn(|c| m[4 * r + c] as f32));
            pose_as_matrix::from_rows(rows)
                .map_err(|e| PyValueError::new_err(format!("{name}[{i}]: {e}")))
        })
        .collect()
}
