//! Typed errors of the simulation.

use std::path::PathBuf;

use thiserror::Error;

/// Everything that can go wrong in a simulation, from bad settings to a full disk.
#[derive(Debug, Error)]
pub enum SimError {
    /// A setting is out of range; the message says which and why.
    #[error("invalid setting: {0}")]
    InvalidConfig(String),
    /// A folder or file could not be created or written.
    #[error("cannot write {}: {source}", path.display())]
    Io {
        /// The path that failed.
        path: PathBuf,
        /// The underlying error.
        #[source]
        source: std::io::Error,
    },
    /// A scenario could not be written in the generator's format.
    #[error("export failed: {0}")]
    Export(String),
    /// A figure could not be drawn or saved.
    #[error("plot {name} failed: {message}")]
    Plot {
        /// Figure name, e.g. `position_error`.
        name: String,
        /// What went wrong.
        message: String,
    },
    /// The core rejected generated data (a bug in the generator if it happens).
    #[error(transparent)]
    Pose(#[from] swarmpose_core::PoseError),
    /// Folders of `simulate --shard` that do not make one whole simulation.
    #[error("cannot merge: {0}")]
    Merge(String),
    /// The worker thread pool could not be built.
    #[error("thread pool: {0}")]
    ThreadPool(String),
}

impl SimError {
    /// An [`SimError::Io`] for `path`.
    pub(crate) fn io(path: impl Into<PathBuf>, source: std::io::Error) -> Self {
        Self::Io {
            path: path.into(),
            source,
        }
    }
}
