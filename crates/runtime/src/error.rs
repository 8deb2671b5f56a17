//! The pipeline's error: whichever layer failed, with its message intact, or what went wrong in
//! its own work (configs, files, options, depth from RGB), with the values and the file named.
//! The dataset generators and the evaluation above it add their own (`mvgrasp::Error`).

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
    #[error("{path}: cannot encode PNG: {source}")]
    Png {
        /// The encoder's error.
        source: png::EncodingError,
        /// The file.
        path: PathBuf,
    },
    /// A config file that cannot be used: the file, and what is wrong in it.
    #[error("{path}: {source}")]
    ConfigFile {
        /// What is wrong.
        source: Box<Error>,
        /// The file.
        path: PathBuf,
    },
    /// A config that is not valid TOML of the expected shape (a syntax error, an unknown key,
    /// a wrong type).
    #[error("not a valid config: {}", mvgrasp_geometry::one_line(&source.to_string()))]
    Toml {
        /// The parser's error.
        source: toml::de::Error,
    },
    /// A config value out of its range.
    #[error("config key {key} = {value}: {expected}")]
    ConfigValue {
        /// The key.
        key: &'static str,
        /// Its value, printed.
        value: String,
        /// What would be valid.
        expected: &'static str,
    },
    /// A JSON file (a manifest, a shard's record, a dataset's cameras) that cannot be read or
    /// written.
    #[error("{path}: cannot {op} the {what}: {}", mvgrasp_geometry::one_line(&source.to_string()))]
    Json {
        /// "read" or "write".
        op: &'static str,
        /// What the file holds.
        what: &'static str,
        /// The parser's error.
        source: serde_json::Error,
        /// The file.
        path: PathBuf,
    },
    /// A safetensors shard that cannot be read or written.
    #[error("{path}: cannot {op} the shard: {source}")]
    Safetensors {
        /// "read" or "write".
        op: &'static str,
        /// The library's error.
        source: safetensors::SafeTensorError,
        /// The file.
        path: PathBuf,
    },
    /// A file of another format or version than the one expected.
    #[error("{path}: format {found:?}, expected {expected:?}")]
    Format {
        /// The format the file names.
        found: String,
        /// The one expected.
        expected: &'static str,
        /// The file.
        path: PathBuf,
    },
    /// A planning option out of its range ([`crate::planner::PlanOptions`]).
    #[error("plan option {name} = {value}: {expected}")]
    PlanOption {
        /// The option (`views`, `distance_m`).
        name: &'static str,
        /// Its value, printed.
        value: String,
        /// What would be valid.
        expected: &'static str,
    },
    /// RGB views that depth cannot be predicted from ([`crate::stereo`]).
    #[error("depth from RGB: {problem}")]
    Stereo {
        /// What is wrong.
        problem: String,
    },
    /// A photographic look that cannot be applied ([`crate::scene::photoreal`]).
    #[error("photographic look: {problem}")]
    Photo {
        /// What is wrong.
        problem: String,
    },
}

/// The domain an [`Error`] belongs to: what went wrong, in the terms of the Python binding's
/// exception classes (one per domain).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ErrorKind {
    /// A mesh, a camera or a stable pose.
    Geometry,
    /// Grasps and grippers.
    Grasp,
    /// Rendering.
    Rendering,
    /// A network's weights, or running it.
    Weights,
    /// Depth images, views or a network the planner cannot use.
    Planning,
    /// A dataset's config, folder, shards or manifest.
    Dataset,
    /// Reading, writing or encoding a file.
    Io,
}

impl Error {
    /// The domain of this error (every variant decides, so a new one must too).
    pub fn kind(&self) -> ErrorKind {
        match self {
            Self::Geometry(_) => ErrorKind::Geometry,
            Self::Grasp(_) => ErrorKind::Grasp,
            Self::Render(_) => ErrorKind::Rendering,
            Self::Infer(_) => ErrorKind::Weights,
            Self::Planning(_) | Self::PlanOption { .. } | Self::Stereo { .. } => {
                ErrorKind::Planning
            }
            Self::Io { .. } | Self::Png { .. } => ErrorKind::Io,
            Self::ConfigFile { .. }
            | Self::Toml { .. }
            | Self::ConfigValue { .. }
            | Self::Json { .. }
            | Self::Safetensors { .. }
            | Self::Format { .. }
            | Self::Photo { .. } => ErrorKind::Dataset,
        }
    }

    /// An [`Error::Io`] for `path`.
    pub fn io(op: &'static str, path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self {
        let path = path.to_path_buf();
        move |source| Self::Io { op, source, path }
    }

    /// An [`Error::Json`] reading or writing the `what` of `path`.
    pub fn json(
        op: &'static str,
        what: &'static str,
        path: &std::path::Path,
    ) -> impl FnOnce(serde_json::Error) -> Self {
        let path = path.to_path_buf();
        move |source| Self::Json {
            op,
            what,
            source,
            path,
        }
    }

    /// This error found in the config file `path` ([`Error::ConfigFile`]).
    pub fn in_config(self, path: &std::path::Path) -> Self {
        Self::ConfigFile {
            source: Box::new(self),
            path: path.to_path_buf(),
        }
    }
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
