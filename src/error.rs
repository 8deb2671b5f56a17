//! The pipeline's error: whichever layer failed, with its message intact.

use std::path::PathBuf;

/// An error from any layer of mvgrasp.
#[derive(Debug, thiserror::Error)]
#[non_exhaustive]
pub enum Error {
    /// Meshes, cameras, stable poses.
    #[error(transparent)]
    Geometry(#[from] mvgrasp_geometry::GeometryError),
    /// Grasps and grippers.
    #[error(transparent)]
    Grasp(#[from] mvgrasp_grasp::GraspError),
    /// Rendering.
    #[error(transparent)]
    Render(#[from] mvgrasp_render::RenderError),
    /// Networks: loading weights, running them.
    #[error(transparent)]
    Infer(#[from] mvgrasp_infer::InferError),
    /// Planning on depth images: images and views, the policy's network.
    #[error(transparent)]
    Planning(#[from] mvgrasp_planner::PlannerError),
    /// A file or folder could not be read or written.
    #[error("{path}: cannot {op}: {source}")]
    Io {
        /// What we were doing: "create", "write", "rename", ...
        op: &'static str,
        /// The underlying error.
        source: std::io::Error,
        /// The file or folder.
        path: PathBuf,
    },
    /// An image could not be encoded.
    #[error("{path}: cannot encode PNG: {detail}")]
    Png {
        /// What the encoder said.
        detail: String,
        /// The file.
        path: PathBuf,
    },
    /// A config file cannot be used.
    #[error("{path}: {detail}")]
    Config {
        /// What is wrong.
        detail: String,
        /// The file.
        path: PathBuf,
    },
    /// A dataset request makes no sense (duplicate names, nothing to do, ...).
    #[error("dataset: {detail}")]
    Dataset {
        /// What is wrong.
        detail: String,
    },
}

impl Error {
    /// An [`Error::Io`] for `path`.
    pub(crate) fn io(
        op: &'static str,
        path: &std::path::Path,
    ) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.to_path_buf();
        move |source| Self::Io { op, source, path }
    }
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
