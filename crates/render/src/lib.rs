#![doc = include_str!("../README.md")]

pub mod adapter;
pub mod camera;
pub mod colors;
pub mod depth8;
pub mod error;
pub mod frame;
pub mod look;
pub mod mesh;
mod pipeline;
mod readback;
pub mod renderer;
mod shadow;
mod targets;

pub use adapter::{BACKEND_ENV, Backend};
pub use camera::{IDENTITY, Intrinsics, View, clip_from_camera, project};
pub use colors::random_colors;
pub use depth8::depth_to_u8;
pub use error::{INSTALL_HINT, RenderError, Result};
pub use frame::Frame;
pub use look::{Light, Lighting, MAX_LIGHTS, Material, Pattern};
pub use mesh::{Colors, MeshInput, Sides};
pub use renderer::{Renderer, Scene};
