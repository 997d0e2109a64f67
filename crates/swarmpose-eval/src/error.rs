//! Errors of reading, writing and comparing trajectories; each names the file and, for
//! malformed content, the line.

use std::path::PathBuf;

/// A failure to read, write or compare trajectories.
#[derive(Debug, thiserror::Error)]
pub enum EvalError {
    /// A file could not be read or written.
    #[error("{path}: {what}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// What was being done ("cannot read", "cannot write").
        what: &'static str,
        /// The system error.
        source: std::io::Error,
    },
    /// A line of a trajectory file is malformed.
    #[error("{path}:{line}: {message}")]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number.
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A trajectory file holds no pose.
    #[error("{path}: no pose in the file")]
    Empty {
        /// The file.
        path: PathBuf,
    },
    /// Index association (KITTI) of trajectories of different lengths.
    #[error(
        "{estimate} has {n_estimate} poses but {ground_truth} has {n_ground_truth}: \
         KITTI files are associated by line, so both need one pose per frame"
    )]
    LengthMismatch {
        /// The estimate's name.
        estimate: String,
        /// Its number of poses.
        n_estimate: usize,
        /// The ground truth's name.
        ground_truth: String,
        /// Its number of poses.
        n_ground_truth: usize,
    },
    /// Too few poses (after association) for the metrics.
    #[error("{what}: {got} pose(s), at least {needed} needed")]
    TooFew {
        /// What was too short.
        what: String,
        /// Poses available.
        got: usize,
        /// Poses needed.
        needed: usize,
    },
    /// A factor for the KITTI segment lengths outside (0, 1].
    #[error(
        "segment length scale {scale}: a factor in (0, 1] of the KITTI lengths (100-800 m) expected"
    )]
    SegmentScale {
        /// The factor given.
        scale: f64,
    },
    /// Trajectories given to a writer disagree in length.
    #[error("{stamps} timestamps for {poses} poses")]
    StampCount {
        /// Number of timestamps.
        stamps: usize,
        /// Number of poses.
        poses: usize,
    },
}

impl EvalError {
    pub(crate) fn parse(path: &std::path::Path, line: usize, message: impl Into<String>) -> Self {
        Self::Parse {
            path: path.to_owned(),
            line,
            message: message.into(),
        }
    }
}
