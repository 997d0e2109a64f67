//! # swarmpose-vision
//!
//! The stereo front end: from rectified grayscale stereo pairs to matched 3D points
//! between consecutive frames, the input of the core estimators.
//!
//! Features come from any [`features::FeatureExtractor`] (SURF as in the paper, or a fast
//! binary detector), so matching and triangulation are written once.
#![deny(missing_docs)]
#![warn(clippy::unwrap_used)]

pub mod features;
pub mod surf;
