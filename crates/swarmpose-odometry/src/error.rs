//! Errors of the odometry engine.

/// Why a frame or a run could not be processed: always bad input (the camera, a setting,
/// a frame); the engine reads and writes no file.
#[derive(Debug, thiserror::Error)]
pub enum OdometryError {
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
    /// A frame of a run failed (the frame's 0-based index and why); the frames before it
    /// were processed.
    #[error("frame {index}: {source}")]
    AtFrame {
        /// 0-based index of the frame.
        index: usize,
        /// Why.
        source: Box<OdometryError>,
    },
}

/// An error type of a run over a stream of frames ([`crate::Odometry::run_two_threads`]):
/// it carries the engine's errors, those of the frames' source, and the frame at which
/// the run stopped.
pub trait RunFailure: From<OdometryError> + Send {
    /// `self` at the frame of 0-based index `index` (an error that already names its
    /// frame keeps it).
    #[must_use]
    fn at_frame(self, index: usize) -> Self;
}

impl RunFailure for OdometryError {
    fn at_frame(self, index: usize) -> Self {
        match self {
            e @ Self::AtFrame { .. } => e,
            e => Self::AtFrame {
                index,
                source: Box::new(e),
            },
        }
    }
}
