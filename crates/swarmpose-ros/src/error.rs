//! Errors of bag reading, message decoding and writing. Every variant names the file (and
//! the topic or message where there is one), in one line.

use std::path::PathBuf;

/// Why a bag, a message or an output could not be read or written.
#[derive(Debug, thiserror::Error)]
pub enum RosError {
    /// A file or directory could not be read or written.
    #[error("{}: {what}: {source}", path.display())]
    Io {
        /// The file.
        path: PathBuf,
        /// What was being done.
        what: &'static str,
        /// The I/O error.
        source: std::io::Error,
    },
    /// The path is neither an `.mcap` file, a `.db3` file nor a rosbag2 folder.
    #[error(
        "{}: not a ROS 2 bag (expected an .mcap or .db3 file, or a folder with metadata.yaml)",
        path.display()
    )]
    NotABag {
        /// The path.
        path: PathBuf,
    },
    /// The container (MCAP records, SQLite tables, metadata.yaml) is malformed.
    #[error("{}: {message}", path.display())]
    Container {
        /// The file.
        path: PathBuf,
        /// What is wrong, and where (byte offset, table, line).
        message: String,
    },
    /// A message's bytes do not decode as its type.
    #[error("{}: topic {topic}, message {index} ({msg_type}): {message}", path.display())]
    Decode {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// 0-based index of the message on its topic.
        index: usize,
        /// The ROS 2 type, `pkg/msg/Name`.
        msg_type: String,
        /// What the decoder said.
        message: String,
    },
    /// The bag holds no usable stereo (or RGB-D) input; the message lists what it holds.
    #[error("{}: {message}", path.display())]
    Topics {
        /// The bag.
        path: PathBuf,
        /// What is missing or ambiguous, with the topics found (type, count).
        message: String,
    },
    /// A `camera_info` is missing, disagrees with its images, or gives no usable rig.
    #[error("{}: {message}", path.display())]
    Calibration {
        /// The bag.
        path: PathBuf,
        /// What is wrong.
        message: String,
    },
    /// An image could not be turned into 8-bit gray (or depth).
    #[error("{}: topic {topic}, message {index}: {message}", path.display())]
    Image {
        /// The bag.
        path: PathBuf,
        /// The topic.
        topic: String,
        /// 0-based index of the message on its topic.
        index: usize,
        /// What is wrong (the encoding, the size).
        message: String,
    },
    /// The MCAP writer failed.
    #[error("{}: cannot write MCAP: {message}", path.display())]
    Write {
        /// The output file.
        path: PathBuf,
        /// The writer's message.
        message: String,
    },
}

impl RosError {
    /// The file the error is about.
    #[must_use]
    pub fn path(&self) -> &std::path::Path {
        match self {
            Self::Io { path, .. }
            | Self::NotABag { path }
            | Self::Container { path, .. }
            | Self::Decode { path, .. }
            | Self::Topics { path, .. }
            | Self::Calibration { path, .. }
            | Self::Image { path, .. }
            | Self::Write { path, .. } => path,
        }
    }
}

/// A message that cannot be decoded (without the bag context: [`RosError::Decode`] adds it).
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error("{0}")]
pub struct CdrError(pub String);
