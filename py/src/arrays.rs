//! NumPy arrays to Rust values and back: meshes, camera matrices, poses. Every error names the
//! argument and what was expected.
//!
//! Every array argument comes in through [`array_of`] (one dtype, as the stubs say) or
//! [`array_cast`] (anything NumPy casts: mesh arrays): of any layout (strides, either order,
//! negative steps, read-only, either byte order, unaligned), it is read in place or copied
//! once, and refused with a `TypeError` (not an array, another dtype) or a `ValueError` (a
//! shape, a size, a value) whose message starts with the argument's name. Its size is
//! checked before anything is copied: an array that only declares a huge shape (zero strides,
//! `np.broadcast_to`) is refused, never allocated.

use mvgrasp_geometry::{Intrinsics, Pose3, TriangleMesh, Vec3, pose_as_matrix};
use numpy::ndarray::Array2;
use numpy::{
    Element, IntoPyArray, PyArray1, PyArray2, PyArrayDescrMethods, PyArrayDyn, PyArrayMethods,
    PyReadonlyArrayDyn, PyUntypedArray, PyUntypedArrayMethods, dtype,
};
use pyo3::exceptions::{PyOverflowError, PyTypeError, PyValueError};
use pyo3::prelude::*;

use crate::errors::mesh_error;

/// The most values one array argument may hold: 2^28, a 16384 x 16384 image (the largest the
/// intrinsics allow), 1 GiB of float32.
pub(crate) const MAX_VALUES: usize = 1 << 28;

/// Refuses a shape of more than [`MAX_VALUES`] values.
fn check_size(name: &str, shape: &[usize]) -> PyResult<()> {
    let values = shape
        .iter()
        .try_fold(1usize, |n, &s| n.checked_mul(s))
        .filter(|&n| n <= MAX_VALUES);
    if values.is_none() {
        return Err(PyValueError::new_err(format!(
            "{name}: shape {shape:?}, more than the {MAX_VALUES} values an array argument may hold"
        )));
    }
    Ok(())
}

/// NumPy's error converting argument `name`, with the name in front: a `TypeError` stays one,
/// a value NumPy cannot convert is a `ValueError`.
fn named(py: Python<'_>, name: &str, error: PyErr) -> PyErr {
    let text = error.value(py).to_string();
    if error.is_instance_of::<PyTypeError>(py) {
        PyTypeError::new_err(format!("{name}: {text}"))
    } else if error.is_instance_of::<PyValueError>(py)
        || error.is_instance_of::<PyOverflowError>(py)
    {
        PyValueError::new_err(format!("{name}: {text}"))
    } else {
        error
    }
}

/// `array` (of dtype `T`, aligned) borrowed for reading.
fn readonly<'py, T: Element>(
    name: &str,
    array: Bound<'py, PyAny>,
) -> PyResult<PyReadonlyArrayDyn<'py, T>> {
    let py = array.py();
    let array = array
        .cast_into::<PyArrayDyn<T>>()
        .map_err(|e| named(py, name, e.into()))?;
    array
        .try_readonly()
        .map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
}

/// Array argument `name` of dtype `T` in any layout, read in place; an array in the other
/// byte order or unaligned is copied first. `TypeError` for something that is not a NumPy
/// array or has another dtype, `ValueError` for more than [`MAX_VALUES`] values.
pub(crate) fn array_of<'py, T: Element>(
    name: &str,
    obj: &Bound<'py, PyAny>,
) -> PyResult<PyReadonlyArrayDyn<'py, T>> {
    let py = obj.py();
    let wanted = dtype::<T>(py);
    let Ok(array) = obj.cast::<PyUntypedArray>() else {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected a NumPy array of {wanted}, got {}",
            obj.get_type().name()?
        )));
    };
    check_size(name, array.shape())?;
    // Only the same values in the other byte order may be copied (into this machine's).
    let given = array.dtype();
    if !(given.kind() == wanted.kind() && given.itemsize() == wanted.itemsize()) {
        return Err(PyTypeError::new_err(format!(
            "{name}: dtype {given}, expected {wanted}"
        )));
    }
    in_place_or_copied(name, array.clone())
}

/// `array` read in place when it is already of dtype `T` and aligned, else its `astype` copy.
fn in_place_or_copied<'py, T: Element>(
    name: &str,
    array: Bound<'py, PyUntypedArray>,
) -> PyResult<PyReadonlyArrayDyn<'py, T>> {
    let py = array.py();
    let wanted = dtype::<T>(py);
    if array.dtype().is_equiv_to(&wanted) && array.is_aligned() {
        return readonly(name, array.into_any());
    }
    let copy = array
        .call_method1("astype", (wanted,))
        .map_err(|e| named(py, name, e))?;
    readonly(name, copy)
}

/// Array argument `name` as dtype `T`: any array NumPy casts to it (as `astype` does), or
/// anything `np.asarray` takes (nested lists). `TypeError` or `ValueError` for what NumPy
/// cannot convert, `ValueError` for more than [`MAX_VALUES`] values (before converting).
pub(crate) fn array_cast<'py, T: Element>(
    name: &str,
    obj: &Bound<'py, PyAny>,
) -> PyResult<PyReadonlyArrayDyn<'py, T>> {
    let py = obj.py();
    let wanted = dtype::<T>(py);
    if obj.is_none() {
        return Err(PyTypeError::new_err(format!(
            "{name}: expected an array of {wanted}, got None"
        )));
    }
    let array = match obj.cast::<PyUntypedArray>() {
        Ok(array) => array.clone(),
        Err(_) => py
            .import("numpy")?
            .call_method1("asarray", (obj,))
            .map_err(|e| named(py, name, e))?
            .cast_into::<PyUntypedArray>()
            .map_err(|e| named(py, name, e.into()))?,
    };
    check_size(name, array.shape())?;
    in_place_or_copied(name, array)
}

/// Refuses NaN and infinities (in float32: a float64 beyond its range is one too).
fn check_finite(name: &str, mut values: impl Iterator<Item = f32>) -> PyResult<()> {
    if values.all(f32::is_finite) {
        return Ok(());
    }
    Err(PyValueError::new_err(format!(
        "{name}: NaN or infinite values (or beyond float32's range)"
    )))
}

/// Refuses a shape that is not `expected`.
pub(crate) fn check_shape(name: &str, shape: &[usize], expected: &[usize]) -> PyResult<()> {
    if shape == expected {
        return Ok(());
    }
    let dims: Vec<String> = expected.iter().map(usize::to_string).collect();
    Err(PyValueError::new_err(format!(
        "{name}: shape {shape:?}, expected ({})",
        dims.join(", ")
    )))
}

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
/// as they are. An empty array is a `ValueError` naming it, as a shape that is not (N, 3) is.
pub(crate) fn mesh_of(
    vertices: &Bound<'_, PyAny>,
    triangles: &Bound<'_, PyAny>,
) -> PyResult<TriangleMesh> {
    let v = array_cast::<f32>("vertices", vertices)?;
    let v = v.as_array();
    if v.ndim() != 2 || v.shape()[1] != 3 || v.shape()[0] == 0 {
        return Err(PyValueError::new_err(format!(
            "vertices: shape {:?}, expected (N, 3) with N >= 1",
            v.shape()
        )));
    }
    let t = array_cast::<i64>("triangles", triangles)?;
    let t = t.as_array();
    if t.ndim() != 2 || t.shape()[1] != 3 || t.shape()[0] == 0 {
        return Err(PyValueError::new_err(format!(
            "triangles: shape {:?}, expected (M, 3) with M >= 1",
            t.shape()
        )));
    }
    let vertices: Vec<Vec3> = v
        .rows()
        .into_iter()
        .map(|r| Vec3::new(r[0], r[1], r[2]))
        .collect();
    let mut tris = Vec::with_capacity(t.shape()[0]);
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

/// The largest side of an image the intrinsics allow, pixels.
const MAX_SIDE_PX: usize = 16384;

/// An image's `(width, height)` from its array's `height` rows and `width` columns: 1 to
/// 16384 pixels a side (the intrinsics' bounds, checked here to name the image).
pub(crate) fn image_size(
    name: &str,
    shape: &[usize],
    height: usize,
    width: usize,
) -> PyResult<(u32, u32)> {
    let side = |n: usize| {
        u32::try_from(n)
            .ok()
            .filter(|&n| (1..=MAX_SIDE_PX as u32).contains(&n))
    };
    match (side(width), side(height)) {
        (Some(w), Some(h)) => Ok((w, h)),
        _ => Err(PyValueError::new_err(format!(
            "{name}: shape {shape:?}, expected 1 to {MAX_SIDE_PX} pixels a side"
        ))),
    }
}

/// A depth image's size and values: (H, W) or (H, W, 1) float32 metres, 1 to 16384 pixels a
/// side; `name` names the argument in errors.
pub(crate) fn depth_of(name: &str, depth: &Bound<'_, PyAny>) -> PyResult<(u32, u32, Vec<f32>)> {
    let depth = array_of::<f32>(name, depth)?;
    let depth = depth.as_array();
    let shape = depth.shape();
    let (height, width) = match *shape {
        [h, w] | [h, w, 1] => (h, w),
        _ => {
            return Err(PyValueError::new_err(format!(
                "{name}: shape {shape:?}, expected (H, W) or (H, W, 1)"
            )));
        }
    };
    let (width, height) = image_size(name, shape, height, width)?;
    Ok((width, height, depth.iter().copied().collect()))
}

/// A boolean mask of an image's pixels, which must be its size (`height`, `width`).
pub(crate) fn mask_of(
    name: &str,
    mask: &Bound<'_, PyAny>,
    width: u32,
    height: u32,
) -> PyResult<Vec<bool>> {
    let m = array_of::<bool>(name, mask)?;
    let m = m.as_array();
    if m.shape() != [height as usize, width as usize] {
        return Err(PyValueError::new_err(format!(
            "{name}: shape {:?}, expected the image's ({height}, {width})",
            m.shape()
        )));
    }
    Ok(m.iter().copied().collect())
}

/// The intrinsics of a 3x3 camera matrix without skew, for a `width` x `height` image (the size
/// of argument `image`, which an error names too: the matrix may not fit the image).
pub(crate) fn intrinsics_of(
    name: &str,
    k: &Bound<'_, PyAny>,
    image: &str,
    width: u32,
    height: u32,
) -> PyResult<Intrinsics> {
    let k = array_of::<f64>(name, k)?;
    let k = k.as_array();
    check_shape(name, k.shape(), &[3, 3])?;
    check_finite(name, k.iter().map(|&x| x as f32))?;
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
    .map_err(|e| {
        PyValueError::new_err(format!(
            "{name} for {image} of {width} x {height} pixels: {e}"
        ))
    })
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
pub(crate) fn pose_of(name: &str, pose: &Bound<'_, PyAny>) -> PyResult<Pose3> {
    let p = array_of::<f64>(name, pose)?;
    let p = p.as_array();
    check_shape(name, p.shape(), &[4, 4])?;
    // Through f32, as a JSON file's pose is read: the same values give the same bits.
    let rows: [[f32; 4]; 4] = std::array::from_fn(|i| std::array::from_fn(|j| p[[i, j]] as f32));
    check_finite(name, rows.iter().flatten().copied())?;
    pose_as_matrix::from_rows(rows).map_err(|e| PyValueError::new_err(format!("{name}: {e}")))
}

/// [`pose_of`] of an optional argument.
pub(crate) fn optional_pose(
    name: &str,
    pose: Option<&Bound<'_, PyAny>>,
) -> PyResult<Option<Pose3>> {
    pose.map(|p| pose_of(name, p)).transpose()
}

/// A pose as a float64 4x4 array (rows).
pub(crate) fn pose_array<'py>(py: Python<'py>, pose: &Pose3) -> Bound<'py, PyArray2<f64>> {
    let rows = pose_as_matrix::to_rows(pose);
    Array2::from_shape_fn((4, 4), |(i, j)| f64::from(rows[i][j])).into_pyarray(py)
}

/// A float32 3-vector as a `(3,)` float64 array.
pub(crate) fn vec3_array<'py>(py: Python<'py>, v: Vec3) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v.to_array().map(f64::from).to_vec())
}

/// One rigid 4x4 pose `(4, 4)` or a batch `(N, 4, 4)` (rows), as a list.
pub(crate) fn poses_of(name: &str, poses: &Bound<'_, PyAny>) -> PyResult<Vec<Pose3>> {
    let p = array_of::<f64>(name, poses)?;
    let p = p.as_array();
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
            let rows: [[f32; 4]; 4] =
                std::array::from_fn(|r| std::array::from_fn(|c| m[4 * r + c] as f32));
            check_finite(&format!("{name}[{i}]"), rows.iter().flatten().copied())?;
            pose_as_matrix::from_rows(rows)
                .map_err(|e| PyValueError::new_err(format!("{name}[{i}]: {e}")))
        })
        .collect()
}
