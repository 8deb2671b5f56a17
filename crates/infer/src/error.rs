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
}

/// `Result` with [`InferError`].
pub type Result<T, E = InferError> = std::result::Result<T, E>;
