#![doc = include_str!("../README.md")]

pub mod analysis;
pub mod collision;
pub mod error;
pub mod grasp;
pub mod gripper;
pub mod gripper_urdf;
pub mod label;
pub mod object;
pub mod physics;
pub mod quality;
pub mod sampling;
mod separation;

pub use analysis::{AnalysedGrasp, Analysis, AnalysisConfig, analyse};
pub use collision::{Collision, CollisionParams, HandShapes, check_collision};
pub use error::{GraspError, Result};
pub use grasp::{Grasp, ImageGrasp, PaperGrasp};
pub use gripper::{Gripper, GripperPreset};
pub use gripper_urdf::{UrdfGripper, UrdfGripperSpec};
pub use label::{GraspLabel, LabelParams, LabelSettings, label_grasps};
pub use object::GraspObject;
pub use sampling::{
    AntipodalAxis, SampledGrasp, SamplingParams, SamplingReport, canonical_frame, sample_antipodal,
    sample_antipodal_axes,
};
