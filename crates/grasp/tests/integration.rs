//! The grasp crate's integration tests in one binary.

#![allow(clippy::unwrap_used, clippy::expect_used, clippy::panic)] // tests may fail loudly

#[path = "../../../tests/support/shared_data.rs"]
mod shared_data;

mod clutter_trial;
mod gripper_urdf;
mod mechanics;
mod physics;
mod pile;
mod quality;
