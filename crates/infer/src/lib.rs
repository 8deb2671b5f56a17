#![doc = include_str!("../README.md")]

pub mod error;
pub mod ops;
pub mod tensor;

pub use error::{InferError, Result};
pub use tensor::Tensor;
