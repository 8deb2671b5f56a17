//! The renderer's integration tests in one binary.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

mod common;

mod batch;
mod errors;
mod geometry;
mod look;
