//! Errors of runs over recorded sequences: the engine's, the sequence's and the outputs'.

use std::path::PathBuf;

use swarmpose_odometry::{OdometryError, RunFailure};

/// Why a run could not read its sequence, process a frame, or write its outputs.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The engine refused a camera, a setting or a frame (bad input).
    #[error(transparent)]
    Engine(#[from] OdometryError),
    /// The sequence could not be read (bad input).
    #[error(transparent)]
    Dataset(#[from] swarmpose_datasets::DatasetError),
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
    /// A run configuration file that cannot be used (bad input).
    #[error("{}configuration: {message}", if path.as_os_str().is_empty() { String::new() } else { format!("{}: ", path.display()) })]
    Config {
        /// The file (empty for a text that came from no file).
        path: PathBuf,
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
    /// A frame of a run failed (the frame's 0-based index and why); the frames before it
    /// were processed.
    #[error("frame {index}: {source}")]
    AtFrame {
        /// 0-based index of the frame.
        index: usize,
        /// Why.
        source: Box<RunError>,
    },
}

impl RunError {
    /// True for bad input (the sequence, a frame, the camera, a setting), false for a
    /// failure to write outputs or to evaluate them.
    #[must_use]
    pub fn is_input(&self) -> bool {
        match self {
            Self::AtFrame { source, .. } => source.is_input(),
            Self::Engine(_) | Self::Dataset(_) | Self::Rgbd { .. } | Self::Config { .. } => true,
            Self::Write { .. } | Self::Eval(_) => false,
        }
    }
}

impl RunFailure for RunError {
    fn at_frame(self, index: usize) -> Self {
        match self {
            e @ Self::AtFrame { .. } => e,
            // The engine's own frame index is the run's: one wrapper, not two.
            Self::Engine(OdometryError::AtFrame { index, source }) => Self::AtFrame {
                index,
                source: Box::new(Self::Engine(*source)),
            },
            e => Self::AtFrame {
                index,
                source: Box::new(e),
            },
        }
    }
}
