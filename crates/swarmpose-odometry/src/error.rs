//! Errors of an odometry run.

use std::path::PathBuf;

/// Why an odometry run could not be done or its outputs not written.
#[derive(Debug, thiserror::Error)]
pub enum OdometryError {
    /// The sequence could not be read (bad input).
    #[error(transparent)]
    Dataset(#[from] swarmpose_datasets::DatasetError),
    /// Too few frames to estimate any motion (bad input).
    #[error("{dir}: {n} frame(s): odometry needs at least 2")]
    TooFewFrames {
        /// The sequence directory.
        dir: PathBuf,
        /// Its number of frames.
        n: usize,
    },
    /// A malformed or missing file of a TUM RGB-D sequence (bad input).
    #[error("{}{}: {message}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    Rgbd {
        /// The file.
        path: PathBuf,
        /// 1-based line, 0 for the whole file.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// An output file could not be written.
    #[error("{path}: cannot write: {message}")]
    Write {
        /// The file.
        path: PathBuf,
        /// The reason.
        message: String,
    },
    /// A trajectory or evaluation error.
    #[error(transparent)]
    Eval(#[from] swarmpose_eval::EvalError),
}

impl OdometryError {
    /// True for bad input (the sequence), false for a failure to write outputs.
    #[must_use]
    pub fn is_input(&self) -> bool {
        matches!(
            self,
            Self::Dataset(_) | Self::TooFewFrames { .. } | Self::Rgbd { .. }
        )
    }
}
