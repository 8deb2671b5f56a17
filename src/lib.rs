//! mvgrasp: 6-DoF parallel-jaw grasp planning from a few RGB cameras, on a laptop CPU.
//!
//! The runtime (the pipeline `planner::plan_grasp`, planning on a sensor's depth and on RGB
//! views, depth from RGB behind [`depth_from_rgb`], the files it reads and writes) is the crate
//! `mvgrasp_runtime`, re-exported here module by module under the same names. This root crate
//! adds what stands above it and that it never imports (its manifest cannot): the RGB-D and
//! grasp dataset generators ([`dataset`], [`grasp_dataset`]), the ranker's data
//! ([`ranker_data`]), the evaluation ([`evaluate`], the
//! `evaluate` command) and the command-line tools ([`cli`]). The work is done by the layered
//! crates (ARCHITECTURE.md): [`geometry`], [`render`], [`grasp`], [`infer`] and
//! `mvgrasp_planner` (planning on depth images from any source; its types are re-exported in
//! [`planner`]).

pub mod cli;
pub mod dataset;
pub mod error;
pub mod evaluate;
pub mod grasp_dataset;
pub mod ranker_data;

pub use error::{Error, ErrorKind, Result, RuntimeError};
pub use mvgrasp_runtime::{
    ObjectReport, ReportParams, convert, depth_from_rgb, geometry, grasp, grasp_image, grasps_file,
    images, infer, lsm, mcap_log, mvs, planner, render, report, scene, sensor_files, stereo,
    sweep_refiner,
};
