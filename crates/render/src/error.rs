//! The one error type of `mvgrasp-render`.

/// What to install when no adapter is found (Debian/Ubuntu package names).
pub const INSTALL_HINT: &str = "install Mesa's CPU drivers: `apt-get install -y \
mesa-vulkan-drivers libvulkan1` (Vulkan, lavapipe) or `apt-get install -y libegl1 \
libgl1-mesa-dri` (GL, llvmpipe)";

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
    /// No graphics adapter (GPU or CPU rasteriser) could be found.
    #[error("no graphics adapter for backend {requested}; {hint}")]
    NoAdapter {
        /// The backend asked for.
        requested: String,
        /// What to install.
        hint: &'static str,
    },
    /// The adapter refused to open a device.
    #[error("opening a device on {adapter} failed: {message}")]
    RequestDevice {
        /// The adapter, name and backend.
        adapter: String,
        /// The backend's message.
        message: String,
    },
    /// The adapter lacks something the renderer needs.
    #[error("adapter {adapter} cannot be used: {missing}")]
    UnsupportedAdapter {
        /// The adapter, name and backend.
        adapter: String,
        /// What is missing.
        missing: String,
    },
    /// A mesh handed to [`crate::Renderer::upload`] is invalid.
    #[error("mesh {mesh_index}: {reason}")]
    InvalidMesh {
        /// Index of the mesh in the uploaded slice.
        mesh_index: usize,
        /// What is wrong, with the values involved.
        reason: String,
    },
    /// A view handed to [`crate::Renderer::render`] is invalid.
    #[error("view {view_index}: {name} = {value} is invalid: {expected}")]
    InvalidView {
        /// Index of the view in the slice.
        view_index: usize,
        /// The field at fault.
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// What would be valid.
        expected: String,
    },
    /// A scene was uploaded by another [`crate::Renderer`].
    #[error("render: the scene belongs to renderer {scene_renderer}, not to renderer {renderer}")]
    ForeignScene {
        /// The renderer the scene was uploaded to.
        scene_renderer: u64,
        /// The renderer asked to draw it.
        renderer: u64,
    },
    /// A request exceeds a device limit.
    #[error("{op}: {what} needs {needed}, the device allows {limit}")]
    TooLarge {
        /// The operation.
        op: &'static str,
        /// The quantity.
        what: &'static str,
        /// The amount needed.
        needed: u64,
        /// The device limit.
        limit: u64,
    },
    /// Mapping a read-back buffer failed.
    #[error("{op}: mapping the read-back buffer failed: {message}")]
    BufferMap {
        /// The operation.
        op: &'static str,
        /// The backend's message.
        message: String,
    },
    /// The graphics backend reported an error (validation, out of memory, device lost).
    #[error("{op}: the graphics backend reported: {message}")]
    Backend {
        /// The operation.
        op: &'static str,
        /// The backend's message.
        message: String,
    },
}

/// `Result` with [`RenderError`].
pub type Result<T, E = RenderError> = std::result::Result<T, E>;
