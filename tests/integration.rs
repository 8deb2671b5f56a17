//! The root package's integration tests in one binary: one link of the whole stack instead of
//! one per file.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

mod common;
#[path = "support/shared_data.rs"]
mod shared_data;

mod cli;
mod evaluate;
mod grasp_dataset;
mod layering;
mod plan;
mod ranker_data;
mod render_depth;
mod rgb;
mod sensor_depth;
