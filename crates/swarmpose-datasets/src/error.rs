//! Errors of the sequence loaders; every variant names the file or directory at fault.

use std::path::PathBuf;

use swarmpose_vision::image::ImageError;

/// Why a sequence or one of its frames could not be loaded.
#[derive(Debug, thiserror::Error)]
pub enum DatasetError {
    /// A required file or directory does not exist.
    #[error("{}: missing ({what})", path.display())]
    Missing {
        /// The path looked for.
        path: PathBuf,
        /// What it should have been.
        what: &'static str,
    },
    /// The directory matches none of the known layouts.
    #[error(
        "{}: unknown sequence layout (expected KITTI image_0/ image_1/ calib.txt, Karlsruhe \
         I1_*.png I2_*.png calib.txt, or EuRoC mav0/cam0 mav0/cam1)",
        dir.display()
    )]
    UnknownLayout {
        /// The directory.
        dir: PathBuf,
    },
    /// A file or directory could not be read.
    #[error("{}: cannot read: {source}", path.display())]
    Io {
        /// The path.
        path: PathBuf,
        /// The I/O error.
        source: std::io::Error,
    },
    /// An image could not be read or decoded (the message names the file).
    #[error(transparent)]
    Image(#[from] ImageError),
    /// A malformed line in a calibration, list or ground-truth file (`FILE:LINE: ...`,
    /// or `FILE: ...` when the problem is the whole file).
    #[error("{}{}: {message}", path.display(), if *line > 0 { format!(":{line}") } else { String::new() })]
    Parse {
        /// The file.
        path: PathBuf,
        /// 1-based line number (0 when the problem is the whole file).
        line: usize,
        /// What is wrong.
        message: String,
    },
    /// A frame of one camera has no partner in the other.
    #[error(
        "{}: frame {key} has no partner in {} ({left} left and {right} right frames): each \
         frame needs both images",
        present.display(),
        other.display()
    )]
    Unpaired {
        /// The first frame present on one side only.
        present: PathBuf,
        /// Its number (or timestamp, nanoseconds).
        key: i64,
        /// Where its partner was looked for (a folder or a list).
        other: PathBuf,
        /// Number of left frames.
        left: usize,
        /// Number of right frames.
        right: usize,
    },
    /// The frames of a folder or list are not numbered one after the other: a gap, a
    /// number given twice, or a file that is not a frame.
    #[error("{}: {message}", path.display())]
    Frames {
        /// The first file at fault (or the missing one).
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// Two images of one sequence have different sizes.
    #[error(
        "image size mismatch: {} is {}x{} but {} is {}x{}",
        first.display(),
        first_size.0,
        first_size.1,
        second.display(),
        second_size.0,
        second_size.1
    )]
    SizeMismatch {
        /// The reference image.
        first: PathBuf,
        /// Its width and height, pixels.
        first_size: (usize, usize),
        /// The image that differs.
        second: PathBuf,
        /// Its width and height, pixels.
        second_size: (usize, usize),
    },
    /// A frame index past the end.
    #[error("{}: frame {index} out of range (the sequence has {len} frames)", dir.display())]
    FrameOutOfRange {
        /// The sequence directory.
        dir: PathBuf,
        /// The index asked for.
        index: usize,
        /// Number of frames.
        len: usize,
    },
    /// The sequence has no frames.
    #[error("{}: no stereo frames found", dir.display())]
    Empty {
        /// The directory searched.
        dir: PathBuf,
    },
}
