//! The one error type of `mvgrasp-render`.

/// Everything that can go wrong in `mvgrasp-render`.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum RenderError {
    /// An image buffer does not match its stated size.
    #[error("{op}: buffer holds {got} values, {width}x{height} needs {expected}")]
    ImageSize {
        /// The operation.
        op: &'static str,
        /// Values found.
        got: usize,
        /// Values needed.
        expected: usize,
        /// Image width, pixels.
        width: u32,
        /// Image height, pixels.
        height: u32,
    },
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
}

/// `Result` with [`RenderError`].
pub type Result<T, E = RenderError> = std::result::Result<T, E>;
