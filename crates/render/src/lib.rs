#![doc = include_str!("../README.md")]

pub mod depth8;
pub mod error;

pub use depth8::depth_to_u8;
pub use error::{RenderError, Result};
