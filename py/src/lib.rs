//! `mvgrasp._native`: the private extension module behind the `mvgrasp` Python package.
//!
//! This crate holds conversions (Rust types to NumPy arrays) and error mapping (Rust errors to
//! the `mvgrasp.MvGraspError` tree) only; every algorithm lives in the Rust crates it calls.
//!
//! Build it with maturin (`maturin build -m py/Cargo.toml`), which sets
//! `PYO3_BUILD_EXTENSION_MODULE` so that the module does not link `libpython`; pyo3's
//! deprecated `extension-module` feature is therefore not used. The crate is not in the
//! workspace's `default-members`, so a bare `cargo build` / `cargo test` needs no Python.

mod arrays;
mod cameras;
mod convert;
mod errors;
mod grasp_dataset;
mod grasps;
mod mesh;
mod networks;
mod objects;
mod planning;
mod render;

/// The native half of the `mvgrasp` package; import `mvgrasp`, not this module.
#[pyo3::pymodule(name = "_native")]
mod native {
    use pyo3::prelude::*;

    #[pymodule_export]
    use crate::cameras::{
        depth_to_points, hemisphere_cameras, intrinsics_preset, load_intrinsics, project_points,
        unproject_pixels,
    };
    #[pymodule_export]
    use crate::errors::{
        CameraError, DatasetError, GraspError, MeshError, MvGraspError, PlanningError, RenderError,
        WeightsError,
    };
    #[pymodule_export]
    use crate::grasp_dataset::{
        generate_grasp_dataset, generate_grasp_shard, grasp_dataset_num_shards,
        read_grasp_manifest, read_grasp_shard, write_grasp_manifest,
    };
    #[pymodule_export]
    use crate::grasps::{
        check_collision, grasp_quality, gripper, physics_trial, robust_quality, sample_grasps,
    };
    #[pymodule_export]
    use crate::mesh::load_mesh;
    #[pymodule_export]
    use crate::networks::{load_network, score_crops};
    #[pymodule_export]
    use crate::objects::{
        builtin_object, mass_properties, mesh_from_arrays, object_categories, stable_poses,
    };
    #[pymodule_export]
    use crate::planning::{plan_depth, plan_mesh, plan_rgb, plan_views, predict_depth};
    #[pymodule_export]
    use crate::render::{generate_rgbd_dataset, random_colors, read_rgbd_folder, render};

    #[pymodule_init]
    fn init(m: &Bound<'_, PyModule>) -> PyResult<()> {
        m.add("__version__", env!("CARGO_PKG_VERSION"))
    }
}
