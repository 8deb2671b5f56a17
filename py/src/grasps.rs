//! Grasp analysis from NumPy: grippers, antipodal sampling, force closure and Ferrari-Canny
//! epsilon, robust quality, collision checks and the rapier trial, each on a mesh given as
//! `(vertices, triangles)` arrays. Settings default to the grasp datasets' (the labels the
//! shipped networks learnt); a `params` dict overrides any of their fields.

use mvgrasp::grasp::physics::{PhysicsObject, simulate_grasp};
use mvgrasp::grasp::quality::{grasp_quality as quality_of, robust_qualities};
use mvgrasp::grasp::{
    Grasp, GraspObject, Gripper, LabelSettings, check_collision as collision_of, sample_antipodal,
};
use pyo3::prelude::*;
use serde::Serialize;
use serde::de::DeserializeOwned;

use crate::arrays::{mesh_of, optional_pose, pose_of, poses_of};
use crate::convert::{from_python, to_python};
use crate::errors::grasp_error;

/// The vertices and triangles arguments (any real and integer dtypes, [`mesh_of`]).
type Vertices<'py> = Bound<'py, PyAny>;
type Triangles<'py> = Bound<'py, PyAny>;

/// The gripper `spec` names: `None` (the grasp datasets' gripper, the Panda), a preset name, a
/// gripper file (`.toml`, `.json`, Dex-Net's `params.json`, `.urdf`), or a dict of
/// [`Gripper`]'s fields (the missing ones the Panda's).
fn gripper_of(spec: Option<&Bound<'_, PyAny>>) -> PyResult<Gripper> {
    let Some(spec) = spec else {
        return Ok(LabelSettings::default().gripper);
    };
    let gripper = if let Ok(name) = spec.extract::<std::path::PathBuf>() {
        Gripper::from_name_or_file(&name.to_string_lossy()).map_err(grasp_error)?
    } else {
        from_python::<Gripper>("gripper", spec, &Gripper::default())?
    };
    gripper.validate().map_err(grasp_error)?;
    Ok(gripper)
}

/// `defaults` with the fields of the `params` dict (if any) put over them.
fn params_of<T: Serialize + DeserializeOwned>(
    params: Option<&Bound<'_, PyAny>>,
    defaults: T,
) -> PyResult<T> {
    match params {
        Some(p) => from_python("params", p, &defaults),
        None => Ok(defaults),
    }
}

/// Runs `work` on the mesh as a [`GraspObject`] with the GIL released; its result as Python
/// values.
fn on_object<'py, T: Serialize + Send>(
    py: Python<'py>,
    vertices: &Vertices<'py>,
    triangles: &Triangles<'py>,
    work: impl FnOnce(&GraspObject) -> mvgrasp::grasp::Result<T> + Send,
) -> PyResult<Bound<'py, PyAny>> {
    let mesh = mesh_of(vertices, triangles)?;
    let result = py
        .detach(|| work(&GraspObject::new(mesh)?))
        .map_err(grasp_error)?;
    to_python(py, &result)
}

/// The gripper `spec` names, as a dict of its fields (see the stubs).
#[pyfunction]
#[pyo3(signature = (spec = None))]
pub(crate) fn gripper<'py>(
    py: Python<'py>,
    spec: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    to_python(py, &gripper_of(spec.as_ref())?)
}

/// Samples collision-free antipodal grasps on the mesh (object frame); the sampling report.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, *, gripper = None, count = 100, table_from_object = None, params = None, seed = 0))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn sample_grasps<'py>(
    py: Python<'py>,
    vertices: Vertices<'py>,
    triangles: Triangles<'py>,
    gripper: Option<Bound<'py, PyAny>>,
    count: usize,
    table_from_object: Option<Bound<'py, PyAny>>,
    params: Option<Bound<'py, PyAny>>,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let gripper = gripper_of(gripper.as_ref())?;
    let mut params = params_of(params.as_ref(), LabelSettings::default().sampling)?;
    params.target_grasps = count;
    let table = optional_pose("table_from_object", table_from_object.as_ref())?;
    on_object(py, &vertices, &triangles, |object| {
        sample_antipodal(object, &gripper, &params, table.as_ref(), seed)
    })
}

/// Closes the gripper at `object_from_gripper` on the mesh: contacts, force closure, epsilon.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, object_from_gripper, *, gripper = None, friction_coef = 0.5, params = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn grasp_quality<'py>(
    py: Python<'py>,
    vertices: Vertices<'py>,
    triangles: Triangles<'py>,
    object_from_gripper: Bound<'py, PyAny>,
    gripper: Option<Bound<'py, PyAny>>,
    friction_coef: f32,
    params: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let pose = pose_of("object_from_gripper", &object_from_gripper)?;
    let gripper = gripper_of(gripper.as_ref())?;
    let wrench = params_of(params.as_ref(), LabelSettings::default().quality.wrench)?;
    on_object(py, &vertices, &triangles, |object| {
        quality_of(object, &pose, &gripper, friction_coef, &wrench)
    })
}

/// Dex-Net's robust Ferrari-Canny quality of one grasp or a batch (object frame), in parallel;
/// one result per grasp.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, object_from_grippers, *, gripper = None, params = None, seed = 0))]
pub(crate) fn robust_quality<'py>(
    py: Python<'py>,
    vertices: Vertices<'py>,
    triangles: Triangles<'py>,
    object_from_grippers: Bound<'py, PyAny>,
    gripper: Option<Bound<'py, PyAny>>,
    params: Option<Bound<'py, PyAny>>,
    seed: u64,
) -> PyResult<Bound<'py, PyAny>> {
    let poses = poses_of("object_from_grippers", &object_from_grippers)?;
    let gripper = gripper_of(gripper.as_ref())?;
    let params = params_of(params.as_ref(), LabelSettings::default().quality)?;
    on_object(py, &vertices, &triangles, |object| {
        robust_qualities(object, &poses, &gripper, &params, seed)
    })
}

/// Whether the open hand, swept along its approach to `object_from_gripper`, meets the object
/// or (with `table_from_object`) the table.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, object_from_gripper, width_m, *, gripper = None, table_from_object = None, params = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn check_collision<'py>(
    py: Python<'py>,
    vertices: Vertices<'py>,
    triangles: Triangles<'py>,
    object_from_gripper: Bound<'py, PyAny>,
    width_m: f32,
    gripper: Option<Bound<'py, PyAny>>,
    table_from_object: Option<Bound<'py, PyAny>>,
    params: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let pose = pose_of("object_from_gripper", &object_from_gripper)?;
    let table = optional_pose("table_from_object", table_from_object.as_ref())?;
    let gripper = gripper_of(gripper.as_ref())?;
    let params = params_of(params.as_ref(), LabelSettings::default().sampling.collision)?;
    on_object(py, &vertices, &triangles, |object| {
        Ok(collision_of(
            object,
            &gripper,
            &pose,
            width_m,
            table.as_ref(),
            &params,
        ))
    })
}

/// The rapier trial: the object resting at `table_from_object`, the gripper comes to
/// `world_from_gripper` (world = table frame), closes, lifts and shakes; the outcome.
#[pyfunction]
#[pyo3(signature = (vertices, triangles, table_from_object, world_from_gripper, width_m, *, gripper = None, params = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn physics_trial<'py>(
    py: Python<'py>,
    vertices: Vertices<'py>,
    triangles: Triangles<'py>,
    table_from_object: Bound<'py, PyAny>,
    world_from_gripper: Bound<'py, PyAny>,
    width_m: f32,
    gripper: Option<Bound<'py, PyAny>>,
    params: Option<Bound<'py, PyAny>>,
) -> PyResult<Bound<'py, PyAny>> {
    let table_from_object = pose_of("table_from_object", &table_from_object)?;
    let grasp = Grasp {
        world_from_gripper: pose_of("world_from_gripper", &world_from_gripper)?,
        width_m,
    };
    let gripper = gripper_of(gripper.as_ref())?;
    let config = LabelSettings::default();
    let params = params_of(params.as_ref(), config.physics)?;
    on_object(py, &vertices, &triangles, |object| {
        let body = PhysicsObject::from_grasp_object(object, &config.physics_shape)?;
        simulate_grasp(&body, &table_from_object, &grasp, &gripper, &params)
    })
}
