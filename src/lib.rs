//! mvgrasp: 6-DoF parallel-jaw grasp planning from a few RGB cameras, on a laptop CPU.
//!
//! This root crate is the pipeline (`planner::plan_grasp`: render the views of an object at
//! rest on a table ([`scene`]), plan on their depth with a shipped GQ-CNN, check the best grasp
//! analytically and in physics) and, above it and never imported by it (a test checks), the
//! RGB-D and grasp dataset generators, the evaluation and the command-line tools; the work is done by the layered crates it re-exports (see ARCHITECTURE.md):
//! [`geometry`], [`render`], [`grasp`], [`infer`], and `mvgrasp_planner` (planning on depth
//! images from any source; its types are re-exported in [`planner`]). Depth comes from the
//! renderer or a sensor, or is predicted from RGB views: the plane sweep ([`stereo`], the
//! default), the multi-view stereo network ([`mvs`]) or the Learnt Stereo Machine ([`lsm`]).
//! [`evaluate`] is the project's evaluation (the `evaluate` command).

pub mod cli;
pub mod convert;
pub mod dataset;
pub mod depth_from_rgb;
pub mod error;
pub mod evaluate;
pub mod grasp_dataset;
pub mod grasp_image;
pub mod grasps_file;
pub mod images;
pub mod lsm;
pub mod mcap_log;
pub mod mvs;
pub mod planner;
pub mod report;
pub mod scene;
pub mod sensor_files;
pub mod stereo;
pub mod sweep_refiner;

pub use error::{Error, ErrorKind, Result};
pub use mvgrasp_geometry as geometry;
pub use mvgrasp_grasp as grasp;
pub use mvgrasp_infer as infer;
pub use mvgrasp_render as render;
pub use report::{ObjectReport, ReportParams};
