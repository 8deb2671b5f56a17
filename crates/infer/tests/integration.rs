//! The runtime's integration tests in one binary.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

mod common;

mod gqcnn_parity;
mod gqcnn_shaped_forward;
mod lsm_parity;
mod mvs_parity;
mod sweep_refiner_parity;
