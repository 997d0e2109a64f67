//! # swarmpose-odometry
//!
//! Stereo visual odometry after the paper's section 7: for every consecutive pair of
//! frames of a [`StereoSequence`](swarmpose_datasets::StereoSequence), the stereo front
//! end, an estimator and the chaining of eq. (2) ([`pipeline`]); the per-frame log and
//! trajectory files ([`output`]) and the plots of figure 17 ([`plots`]); RGB-D input in
//! the TUM layout ([`rgbd`]); a built-in synthetic stereo sequence rendered along a
//! known path, for runs without data ([`synthetic`]). Measured results: `RESULTS.md`
//! beside this crate's manifest.
#![deny(missing_docs)]
#![warn(clippy::unwrap_used)]

pub mod error;
pub mod output;
pub mod pipeline;
pub mod plots;
pub mod rgbd;
pub mod synthetic;

pub use error::OdometryError;
pub use pipeline::{
    DisparityOffset, FrameRecord, OdometryConfig, OdometryRun, StageTimes, Status, run,
};
