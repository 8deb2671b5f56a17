//! The one error type of `mvgrasp-infer`.

/// Everything that can go wrong in `mvgrasp-infer`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum InferError {
    /// A tensor's data does not fill its shape.
    #[error("{op}: shape {shape:?} needs {expected} values, got {got}")]
    DataLength {
        /// The operation.
        op: &'static str,
        /// The shape asked for.
        shape: Vec<usize>,
        /// Values the shape needs.
        expected: usize,
        /// Values given.
        got: usize,
    },
    /// An op got a tensor of the wrong shape.
    #[error("{op}: expected shape {expected}, got {got:?}")]
    ShapeMismatch {
        /// The operation.
        op: &'static str,
        /// What the op needs, in words ("[batch, features]").
        expected: String,
        /// The shape it got.
        got: Vec<usize>,
    },
    /// An op's parameter is out of its range (a zero stride, a negative epsilon, ...).
    #[error("{op}: {name} = {value}, expected {expected}")]
    InvalidParameter {
        /// The operation.
        op: &'static str,
        /// The parameter's name.
        name: &'static str,
        /// The value given, as text.
        value: String,
        /// What the op needs, in words ("at least 1").
        expected: &'static str,
    },
    /// An axis beyond a tensor's rank.
    #[error("{op}: axis {axis} is out of range for a tensor of rank {rank}")]
    AxisOutOfRange {
        /// The operation.
        op: &'static str,
        /// The axis asked for.
        axis: usize,
        /// The tensor's rank.
        rank: usize,
    },
    /// A model's files cannot be used.
    #[error("{path}: {detail}")]
    Model {
        /// What is wrong.
        detail: String,
        /// The file.
        path: std::path::PathBuf,
    },
    /// A weight tensor is missing or has the wrong shape.
    #[error("{path}: tensor {name}: {detail}")]
    Weight {
        /// The tensor's name.
        name: String,
        /// What is wrong ("missing", "shape [3, 4], expected [4, 3]", ...).
        detail: String,
        /// The weights file.
        path: std::path::PathBuf,
    },
}

/// `Result` with [`InferError`].
pub type Result<T, E = InferError> = std::result::Result<T, E>;
