//! The pipeline's error: whichever layer failed, with its message intact.

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
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
