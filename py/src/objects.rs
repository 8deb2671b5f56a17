//! Objects: the built-in procedural library, meshes from arrays, mass properties and the poses
//! an object rests in.

use mvgrasp_geometry::objects::generate;
use mvgrasp_geometry::{Category, RestingPoses};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::arrays::{MeshArrays, mesh_arrays, mesh_of, pose_array, vec3_array};
use crate::errors::mesh_error;

/// The built-in object categories, in the library's order.
#[pyfunction]
pub(crate) fn object_categories() -> Vec<&'static str> {
    Category::ALL.iter().map(|c| c.name()).collect()
}

/// The `index`-th built-in object of `category` under the library `seed`, as
/// `(vertices, triangles)`: a closed mesh in metres resting on z = 0, the same one the CLI's
/// `--object CATEGORY:INDEX` and the datasets use. Raises `ValueError` for an unknown category.
#[pyfunction]
#[pyo3(signature = (category = "mug", index = 0, seed = 0))]
pub(crate) fn builtin_object<'py>(
    py: Python<'py>,
    category: &str,
    index: u32,
    seed: u64,
) -> PyResult<MeshArrays<'py>> {
    let category: Category = category.parse().map_err(mesh_error)?;
    let object = py
        .detach(|| generate(category, index, seed))
        .map_err(mesh_error)?;
    mesh_arrays(py, &object.mesh)
}

/// Checks `(vertices, triangles)` as a mesh file is checked (indices in range, finite vertices)
/// and returns them as float32 and uint32 arrays, zero-area triangles dropped. Any real dtype
/// and any integer dtype go in (a `trimesh.Trimesh`'s `vertices` and `faces` as they are).
#[pyfunction]
pub(crate) fn mesh_from_arrays<'py>(
    py: Python<'py>,
    vertices: Bound<'py, PyAny>,
    triangles: Bound<'py, PyAny>,
) -> PyResult<MeshArrays<'py>> {
    mesh_arrays(py, &mesh_of(&vertices, &triangles)?)
}

/// Volume, mass, centre of mass and inertia of a mesh at `density_kg_m3`, as a dict:
/// `volume_m3`, `mass_kg`, `center_of_mass` (3,), `inertia_kg_m2` (3, 3) about the centre of
/// mass, `watertight`, and `from_convex_hull` (a mesh that is not watertight has no inside:
/// its convex hull's figures are given).
#[pyfunction]
#[pyo3(signature = (vertices, triangles, density_kg_m3 = 1000.0))]
pub(crate) fn mass_properties<'py>(
    py: Python<'py>,
    vertices: Bound<'py, PyAny>,
    triangles: Bound<'py, PyAny>,
    density_kg_m3: f32,
) -> PyResult<Bound<'py, PyDict>> {
    let mesh = mesh_of(&vertices, &triangles)?;
    let (facts, watertight) = py
        .detach(|| {
            mesh.mass_facts(density_kg_m3)
                .map(|f| (f, mesh.is_watertight()))
        })
        .map_err(mesh_error)?;
    let inertia: Vec<Vec<f64>> = facts
        .inertia_kg_m2
        .iter()
        .map(|row| row.iter().map(|&v| f64::from(v)).collect())
        .collect();
    let dict = PyDict::new(py);
    dict.set_item("volume_m3", f64::from(facts.volume_m3))?;
    dict.set_item("mass_kg", f64::from(facts.mass_kg))?;
    dict.set_item("center_of_mass", vec3_array(py, facts.center_of_mass))?;
    dict.set_item("inertia_kg_m2", PyArray2::from_vec2(py, &inertia)?)?;
    dict.set_item("watertight", watertight)?;
    dict.set_item("from_convex_hull", facts.from_convex_hull)?;
    Ok(dict)
}

/// The poses a mesh rests in on a table, most probable first, each a dict: `probability`,
/// `table_from_object` (4x4: the resting face on z = 0, the centre of mass above the origin),
/// `face_normal` (3,) in the object frame, `face_area_m2`, `tipping_angle_rad`, `marginal`
/// (it rolls or topples at a touch) and `offered` (whether the planner and the datasets use it:
/// the poses that are not marginal, or all of them for an object that has no other; the CLI's
/// `--stable-pose K` is the K-th offered pose).
#[pyfunction]
pub(crate) fn stable_poses<'py>(
    py: Python<'py>,
    vertices: Bound<'py, PyAny>,
    triangles: Bound<'py, PyAny>,
) -> PyResult<Bound<'py, PyList>> {
    let mesh = mesh_of(&vertices, &triangles)?;
    let rest = py.detach(|| RestingPoses::of(&mesh)).map_err(mesh_error)?;
    let poses = PyList::empty(py);
    for (i, pose) in rest.all.iter().enumerate() {
        let dict = PyDict::new(py);
        dict.set_item("probability", f64::from(pose.probability))?;
        dict.set_item("table_from_object", pose_array(py, &pose.table_from_object))?;
        dict.set_item("face_normal", vec3_array(py, pose.face_normal))?;
        dict.set_item("face_area_m2", f64::from(pose.face_area_m2))?;
        dict.set_item("tipping_angle_rad", f64::from(pose.tipping_angle_rad))?;
        dict.set_item("marginal", pose.marginal)?;
        dict.set_item("offered", rest.offered.contains(&i))?;
        poses.append(dict)?;
    }
    Ok(poses)
}
