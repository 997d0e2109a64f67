//! Errors of the odometry engine and of the runs over sequences.

use std::path::PathBuf;

/// Why a frame or a run could not be processed, or its outputs not written.
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
    /// A camera (or RGB-D noise model) that is not valid, or a frame of the wrong kind
    /// for the engine (bad input).
    #[error("camera: {message}")]
    Camera {
        /// What is wrong.
        message: String,
    },
    /// A setting of [`crate::OdometryConfig`] out of its range (bad input).
    #[error("{message}")]
    Config {
        /// What is wrong, naming the setting.
        message: String,
    },
    /// A frame that does not fit the camera, or a timestamp that does not increase (bad
    /// input); the engine's state is unchanged.
    #[error("{message}")]
    Frame {
        /// What is wrong.
        message: String,
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
    /// A frame of a run failed (the frame's 0-based index and why); the frames before it
    /// were processed.
    #[error("frame {index}: {source}")]
    AtFrame {
        /// 0-based index of the frame.
        index: usize,
        /// Why.
        source: Box<OdometryError>,
    },
    /// A trajectory or evaluation error.
    #[error(transparent)]
    Eval(#[from] swarmpose_eval::EvalError),
}

impl OdometryError {
    /// True for bad input (the sequence, a frame, the camera), false for a failure to
    /// write outputs.
    #[must_use]
    pub fn is_input(&self) -> bool {
        if let Self::AtFrame { source, .. } = self {
            return source.is_input();
        }
        matches!(
            self,
            Self::Dataset(_)
                | Self::TooFewFrames { .. }
                | Self::Rgbd { .. }
                | Self::Camera { .. }
                | Self::Config { .. }
                | Self::Frame { .. }
        )
    }
}
