#![doc = include_str!("../README.md")]

pub mod camera;
pub mod error;
pub mod mesh;
pub mod objects;
pub mod properties;
pub mod raycast;
pub mod resting;
pub mod rounding;
pub mod stable_poses;
pub mod views;

pub mod pose_as_matrix;

pub use camera::{Camera, Intrinsics, IntrinsicsPreset, pose_from_rows, read_camera_pose, read_tf};
pub use error::{GeometryError, Result, one_line};
pub use mesh::{
    LoadOptions, TriangleMesh, UrdfGeometryKind, UrdfModel, load_mesh, load_mesh_with, write_obj,
};
pub use objects::{Category, GeneratedObject, MarchingParams, ObjectSpec, default_object};
/// The math types of every public API: parry's (glam 0.33 through glamx), f32, metres.
pub use parry3d::math::{Mat3, Pose3, Rot3, Vec3};
pub use properties::{DecompositionParams, MassFacts, Topology};
pub use raycast::{RayCaster, RayHit};
pub use resting::RestingPoses;
pub use stable_poses::{StablePose, StablePoseParams, stable_poses};
pub use views::HemisphereLayout;
