//! # swarmpose-odometry
//!
//! Online stereo (and RGB-D) visual odometry: a streaming engine ([`Odometry`]) that
//! takes one frame at a time and returns its pose at once, with its status, inliers,
//! stage timings, the covariance of its motion and the disparity correction in use.
//! Memory does not grow with the sequence. One module per stage:
//!
//! | stage | module |
//! |---|---|
//! | frame intake (the camera, frames, checks) | [`intake`] |
//! | front end (features, stereo matching, RGB-D depth) | [`frontend`] |
//! | estimate (matching, robust estimator) | `estimate` (private) |
//! | reprojection refinement and covariance | [`refine`] |
//! | the solvers' base: pose update, Huber loss, damping loop, Schur elimination | `nls` (private) |
//! | self-calibration of the disparity correction | [`selfcal`] |
//! | the state machine from frames to poses | [`tracker`] |
//! | the engine | [`engine`] |
//!
//! The engine runs on the caller's thread ([`Odometry::track`]), or on two
//! ([`Odometry::run_two_threads`]: the front end of the next frame beside the back end
//! of this one, with the same results).
//!
//! The engine reads and writes no file: runs over recorded sequences, output files, plots
//! and synthetic sequences are in the `swarmpose-runs` crate above it. Measured results:
//! `RESULTS.md` beside this crate's manifest.
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod config;
#[cfg(feature = "serde")]
mod config_serde;
pub mod engine;
pub mod error;
mod estimate;
pub mod frontend;
pub mod intake;
mod nls;
pub mod record;
pub mod rectification;
pub mod refine;
pub mod selfcal;
pub mod tracker;
pub mod window;
pub mod working;

pub use config::{Calibration, MIN_INLIERS, OdometryConfig};
pub use engine::{Odometry, OdometryBuilder, OwnedStereoFrame, RunEnd};
pub use error::{OdometryError, RunFailure};
pub use intake::{DepthView, RgbdInput, StereoCamera, StereoInput};
pub use record::{Counts, FrameResult, Inlier, Reason, StageTimes, Status};
pub use selfcal::{CorrectionModel, Decision, SelfCalConfig};
