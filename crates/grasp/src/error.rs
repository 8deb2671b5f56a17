//! The one error type of `mvgrasp-grasp`.

/// Everything that can go wrong in `mvgrasp-grasp`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum GraspError {
    /// A parameter is out of its valid range.
    #[error("{op}: {name} = {value} is invalid: {expected}")]
    InvalidParameter {
        /// The operation.
        op: &'static str,
        /// The parameter.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// What would be valid.
        expected: &'static str,
    },
    /// A gripper file cannot be used.
    #[error("gripper file {}: {detail}", path.display())]
    GripperFile {
        /// What is wrong.
        detail: String,
        /// The file.
        path: std::path::PathBuf,
    },
    /// The object cannot be analysed.
    #[error("object {}: {detail}", path.display())]
    Object {
        /// What is wrong.
        detail: String,
        /// The mesh's file.
        path: std::path::PathBuf,
    },
}

/// `Result` with [`GraspError`].
pub type Result<T, E = GraspError> = std::result::Result<T, E>;
