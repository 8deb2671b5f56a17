#![doc = include_str!("../README.md")]

pub mod bench;
pub mod error;
mod gemm;
pub mod model;
pub mod ops;
pub mod parallel;
pub mod tensor;
#[cfg(test)]
mod testing;

pub use error::{InferError, Result};
pub use model::{Gqcnn, GqcnnWorkspace, Lsm, Mvs, MvsDepth, SweepRefiner};
pub use parallel::Parallelism;
pub use tensor::Tensor;
