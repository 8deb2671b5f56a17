//! mvgrasp's error: the runtime's ([`RuntimeError`]: geometry, grasps, rendering, networks,
//! planning, files), and those of the dataset generators and the evaluation that stand above
//! it. The runtime never sees the second kind: it cannot import this crate.

use std::path::PathBuf;

pub use mvgrasp_runtime::{Error as RuntimeError, ErrorKind};

/// An error of mvgrasp: the runtime's, or a dataset's or the evaluation's.
#[derive(Debug, thiserror::Error)]
pub enum Error {
    /// An error of the runtime or a layer below it.
    #[error(transparent)]
    Runtime(#[from] RuntimeError),
    /// An evaluation that cannot go on: its object set, its record folder or its options.
    #[error("evaluate: {problem}")]
    Evaluate {
        /// What is wrong (naming the file or option).
        problem: String,
    },
    /// A dataset asked of no objects.
    #[error("dataset: no objects to make a dataset of")]
    NoObjects,
    /// Two objects of a dataset with one name.
    #[error("dataset: two objects are named {name:?}; rename one file or list each file once")]
    DuplicateObject {
        /// The name.
        name: String,
    },
    /// A shard index past the dataset.
    #[error("dataset: shard {index} does not exist: the dataset has {num_shards}")]
    NoSuchShard {
        /// The index asked for.
        index: usize,
        /// Shards the dataset has.
        num_shards: usize,
    },
    /// A folder that holds a dataset made with another config or other objects.
    #[error("{path}: this folder holds a dataset made {reason}; use another folder or delete it")]
    ForeignDataset {
        /// The dataset's manifest (or settings file).
        path: PathBuf,
        /// How it differs: "with another config", "by another version of mvgrasp (...)".
        reason: String,
    },
    /// A finished shard made with another config or other objects.
    #[error(
        "{path}: shard {index} was made with another config or other objects (plan hash \
         {found:?}, this one {expected:?}); use another folder or delete it"
    )]
    ForeignShard {
        /// The shard.
        index: usize,
        /// The hash it records (empty: made before hashes were recorded).
        found: String,
        /// This plan's hash.
        expected: String,
        /// The shard's file.
        path: PathBuf,
    },
    /// A shard file that cannot be read as one of the grasp dataset's
    /// ([`crate::grasp_dataset::read_shard`]).
    #[error("{path}: not a readable grasp-dataset shard: {problem}")]
    Shard {
        /// What is wrong: the file unreadable, a column missing or of another type or shape.
        problem: String,
        /// The file.
        path: PathBuf,
    },
    /// A dataset with nothing to show.
    #[error("{path}: the dataset has no datapoint to preview")]
    EmptyDataset {
        /// The dataset folder.
        path: PathBuf,
    },
}

/// The layers' errors become the runtime's, as there.
macro_rules! through_runtime {
    ($($layer:ty),* $(,)?) => {$(
        impl From<$layer> for Error {
            fn from(error: $layer) -> Self {
                Self::Runtime(error.into())
            }
        }
    )*};
}

through_runtime!(
    mvgrasp_geometry::GeometryError,
    mvgrasp_grasp::GraspError,
    mvgrasp_render::RenderError,
    mvgrasp_infer::InferError,
    mvgrasp_planner::PlannerError,
);

impl Error {
    /// The domain of this error: the runtime's own, or a dataset's (the evaluation's too).
    pub fn kind(&self) -> ErrorKind {
        match self {
            Self::Runtime(e) => e.kind(),
            Self::Evaluate { .. }
            | Self::NoObjects
            | Self::DuplicateObject { .. }
            | Self::NoSuchShard { .. }
            | Self::ForeignDataset { .. }
            | Self::ForeignShard { .. }
            | Self::Shard { .. }
            | Self::EmptyDataset { .. } => ErrorKind::Dataset,
        }
    }

    /// An [`RuntimeError::Io`] for `path`.
    pub fn io(op: &'static str, path: &std::path::Path) -> impl FnOnce(std::io::Error) -> Self {
        let io = RuntimeError::io(op, path);
        move |source| Self::Runtime(io(source))
    }

    /// An [`RuntimeError::Json`] reading or writing the `what` of `path`.
    pub fn json(
        op: &'static str,
        what: &'static str,
        path: &std::path::Path,
    ) -> impl FnOnce(serde_json::Error) -> Self {
        let json = RuntimeError::json(op, what, path);
        move |source| Self::Runtime(json(source))
    }

    /// This error found in the config file `path` ([`RuntimeError::ConfigFile`]).
    pub fn in_config(self, path: &std::path::Path) -> Self {
        match self {
            Self::Runtime(e) => Self::Runtime(e.in_config(path)),
            other => other,
        }
    }
}

/// `Result` with [`Error`].
pub type Result<T, E = Error> = std::result::Result<T, E>;
