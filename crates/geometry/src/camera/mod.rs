//! Pinhole cameras in the OpenCV convention (x right, y down, z forward along the optical axis):
//! intrinsics with named presets and the Berkeley `.intr` format, extrinsics `world_from_camera`
//! with a look-at constructor and the Berkeley `.tf` format, projection and depth back-projection.

mod extrinsics;
mod intrinsics;

pub use extrinsics::{Camera, pose_from_rows, read_camera_pose, read_tf};
pub use intrinsics::{Intrinsics, IntrinsicsPreset};
