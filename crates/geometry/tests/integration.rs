//! The geometry crate's integration tests in one binary.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

mod common;

mod bad_inputs;
mod procedural_poses;
mod real_calibration;
mod real_meshes;
