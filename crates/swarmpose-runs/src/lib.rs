//! # swarmpose-runs
//!
//! The odometry engine ([`swarmpose_odometry::Odometry`]) run over recorded sequences:
//! everything around the engine that reads or writes files. The engine itself knows no
//! dataset, file format or plot.
//!
//! | what | module |
//! |---|---|
//! | loops that feed a sequence's frames to the engine, one at a time | [`batch`] |
//! | the configuration of a run, written with every run and read back | [`config`] |
//! | output rows and files (trajectory, per-frame log, covariances, summary) | [`output`] |
//! | the plots of figure 17 | [`plots`] |
//! | TUM RGB-D input | [`rgbd`] |
//! | synthetic sequences with known motion (rendered, or features without images) | [`synthetic`] |
//! | errors of runs | [`error`] |
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod batch;
pub mod config;
pub mod error;
pub mod output;
pub mod output_dir;
pub mod plots;
pub mod rgbd;
pub mod synthetic;

pub use error::RunError;
