//! mvgrasp's runtime: what `plan` runs, and what a robot embedding mvgrasp links.
//!
//! The pipeline (`planner::plan_grasp`: render the views of an object at rest on a table
//! ([`scene`]), plan on their depth with a shipped GQ-CNN or the multi-view planner, check the
//! best grasp analytically and in physics), planning on a sensor's depth images
//! ([`planner::sensor`]) and on RGB views ([`planner::rgb`]), depth from RGB behind one
//! interface ([`depth_from_rgb`]: the plane sweep [`stereo`], the sweep refiner
//! [`sweep_refiner`], the multi-view stereo network [`mvs`], the Learnt Stereo Machine
//! [`lsm`]), and the files it reads and writes ([`sensor_files`], [`grasps_file`],
//! [`mcap_log`], [`images`], [`grasp_image`]). The dataset generators, the evaluation and the
//! command-line tools are the root package `mvgrasp`, above this crate (ARCHITECTURE.md);
//! `mvgrasp` re-exports every module here under the same name.

pub mod convert;
pub mod depth_from_rgb;
pub mod error;
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
