//! Grasp-dataset shards for Python and for many machines (the Ray launcher calls these).

use std::path::PathBuf;

use mvgrasp::cli::LibraryArgs;
use mvgrasp::dataset::ObjectSource;
use mvgrasp::grasp_dataset::{
    DatasetPlan, GraspDatasetConfig, ShardColumn, generate, generate_shard, read_manifest,
    read_shard,
};
use mvgrasp::render::Renderer;
use numpy::{Element, PyArray1, PyArrayMethods};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use safetensors::Dtype;

use crate::convert::to_python;
use crate::errors::dataset_error;
use crate::render::backend_of;

/// The plan of a dataset: its config (a TOML file, or the defaults) and objects (mesh files or
/// folders, or the built-in library).
fn plan(
    config: Option<PathBuf>,
    meshes: Option<Vec<PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
) -> PyResult<DatasetPlan> {
    let (sources, config) = inputs(config, meshes, per_category, categories, library_seed)?;
    DatasetPlan::new(&sources, &config).map_err(dataset_error)
}

/// The objects and the config of a dataset.
fn inputs(
    config: Option<PathBuf>,
    meshes: Option<Vec<PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
) -> PyResult<(Vec<ObjectSource>, GraspDatasetConfig)> {
    let config = match config {
        Some(path) => GraspDatasetConfig::from_file(&path).map_err(dataset_error)?,
        None => GraspDatasetConfig::default(),
    };
    let sources = library_sources(meshes, per_category, categories, library_seed)?;
    Ok((sources, config))
}

/// The objects of a dataset: mesh files or folders, or (when `meshes` is `None`) the built-in
/// library, `per_category` objects of each of `categories` (default all).
pub(crate) fn library_sources(
    meshes: Option<Vec<PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
) -> PyResult<Vec<ObjectSource>> {
    let categories = categories
        .unwrap_or_default()
        .iter()
        .map(|c| c.parse().map_err(|e| PyValueError::new_err(format!("{e}"))))
        .collect::<PyResult<Vec<_>>>()?;
    let library = LibraryArgs {
        mesh: meshes.unwrap_or_default(),
        per_category,
        categories,
        library_seed,
    };
    library
        .sources()
        .map_err(|e| PyValueError::new_err(e.to_string()))
}

/// How many shards the dataset has.
#[pyfunction]
#[pyo3(signature = (config = None, meshes = None, per_category = 1, categories = None, library_seed = 0))]
pub(crate) fn grasp_dataset_num_shards(
    config: Option<PathBuf>,
    meshes: Option<Vec<PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
) -> PyResult<usize> {
    Ok(plan(config, meshes, per_category, categories, library_seed)?.num_shards())
}

/// Makes shard `shard` in `out` (skipped when finished); its record.
#[pyfunction]
#[pyo3(signature = (out, shard, config = None, meshes = None, per_category = 1, categories = None, library_seed = 0, backend = "auto"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn generate_grasp_shard<'py>(
    py: Python<'py>,
    out: PathBuf,
    shard: usize,
    config: Option<PathBuf>,
    meshes: Option<Vec<PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let plan = plan(config, meshes, per_category, categories, library_seed)?;
    let backend = backend_of(backend)?;
    let record = py.detach(|| -> mvgrasp::Result<_> {
        std::fs::create_dir_all(&out).map_err(mvgrasp::Error::io("create", &out))?;
        let renderer = Renderer::new(backend)?;
        generate_shard(&renderer, &plan, &out, shard)
    });
    to_python(py, &record.map_err(dataset_error)?)
}

/// Writes `out/dataset.json` from the shards finished there; the manifest.
#[pyfunction]
#[pyo3(signature = (out, config = None, meshes = None, per_category = 1, categories = None, library_seed = 0))]
pub(crate) fn write_grasp_manifest(
    py: Python<'_>,
    out: PathBuf,
    config: Option<PathBuf>,
    meshes: Option<Vec<PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
) -> PyResult<Bound<'_, PyAny>> {
    let plan = plan(config, meshes, per_category, categories, library_seed)?;
    let manifest = py
        .detach(|| plan.write_manifest(&out))
        .map_err(dataset_error)?;
    to_python(py, &manifest)
}

/// Makes every unfinished shard in `out` and the manifest, with the Rust generator's own loop
/// (`mvgrasp::grasp_dataset::generate`: the same checks and bytes as the `grasp_dataset`
/// command); the manifest.
#[pyfunction]
#[pyo3(signature = (out, config = None, meshes = None, per_category = 1, categories = None, library_seed = 0, backend = "auto"))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn generate_grasp_dataset<'py>(
    py: Python<'py>,
    out: PathBuf,
    config: Option<PathBuf>,
    meshes: Option<Vec<PathBuf>>,
    per_category: u32,
    categories: Option<Vec<String>>,
    library_seed: u64,
    backend: &str,
) -> PyResult<Bound<'py, PyAny>> {
    let (sources, config) = inputs(config, meshes, per_category, categories, library_seed)?;
    let backend = backend_of(backend)?;
    let manifest = py
        .detach(|| -> mvgrasp::Result<_> {
            let renderer = Renderer::new(backend)?;
            generate(&renderer, &sources, &config, &out, false)?;
            read_manifest(&out)
        })
        .map_err(dataset_error)?;
    to_python(py, &manifest)
}

/// Every column of the shard at `path` as a NumPy array (its dtype and shape, datapoints
/// first), after checking it against the format (`mvgrasp::grasp_dataset::COLUMNS`).
/// Raises `mvgrasp.DatasetError` naming the file and the fault.
#[pyfunction]
pub(crate) fn read_grasp_shard(py: Python<'_>, path: PathBuf) -> PyResult<Bound<'_, PyDict>> {
    let columns = py.detach(|| read_shard(&path)).map_err(dataset_error)?;
    let out = PyDict::new(py);
    for column in columns {
        let array = match column.dtype {
            Dtype::F32 => column_array(py, &column, f32::from_le_bytes)?,
            Dtype::U8 => column_array(py, &column, u8::from_le_bytes)?,
            Dtype::I8 => column_array(py, &column, i8::from_le_bytes)?,
            Dtype::U32 => column_array(py, &column, u32::from_le_bytes)?,
            Dtype::U64 => column_array(py, &column, u64::from_le_bytes)?,
            other => {
                return Err(PyValueError::new_err(format!(
                    "{}: column {} of dtype {other:?}, which the format has none of",
                    path.display(),
                    column.name
                )));
            }
        };
        out.set_item(column.name, array)?;
    }
    Ok(out)
}

/// A column's little-endian elements as an array of its shape.
fn column_array<'py, T: Element, const N: usize>(
    py: Python<'py>,
    column: &ShardColumn,
    from_le_bytes: fn([u8; N]) -> T,
) -> PyResult<Bound<'py, PyAny>> {
    let values: Vec<T> = column
        .data
        .chunks_exact(N)
        .map(|b| from_le_bytes(b.try_into().unwrap_or([0; N])))
        .collect();
    Ok(PyArray1::from_vec(py, values)
        .reshape(column.shape.as_slice())?
        .into_any())
}

/// Reads `dir/dataset.json` (checked to be a grasp-dataset manifest); its content.
#[pyfunction]
pub(crate) fn read_grasp_manifest(py: Python<'_>, dir: PathBuf) -> PyResult<Bound<'_, PyAny>> {
    let manifest = read_manifest(&dir).map_err(dataset_error)?;
    to_python(py, &manifest)
}
