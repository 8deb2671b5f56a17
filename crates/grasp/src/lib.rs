#![doc = include_str!("../README.md")]

pub mod error;
pub mod grasp;
pub mod gripper;
pub mod object;
pub mod physics;
pub mod quality;

pub use error::{GraspError, Result};
pub use grasp::{Grasp, ImageGrasp, PaperGrasp};
pub use gripper::{Gripper, GripperPreset};
pub use object::GraspObject;
