//! mvgrasp: 6-DoF parallel-jaw grasp planning from a few RGB cameras, on a laptop CPU.
//!
//! This root crate is the pipeline and the command-line tools; the work is done by the layered
//! crates it re-exports (see ARCHITECTURE.md): [`geometry`], [`render`], [`grasp`], [`infer`].
//! Today the pipeline stops at describing an object for planning: its mesh facts, the poses it
//! rests in, and the cameras that will look at it.

pub mod cli;
pub mod convert;
pub mod dataset;
pub mod error;
pub mod grasp_dataset;
pub mod grasp_image;
pub mod planner;
pub mod report;

pub use error::{Error, Result};
pub use mvgrasp_geometry as geometry;
pub use mvgrasp_grasp as grasp;
pub use mvgrasp_infer as infer;
pub use mvgrasp_render as render;
pub use report::{ObjectReport, ReportParams};
