//! # swarmpose-vision
//!
//! The stereo front end: from rectified grayscale stereo pairs to matched 3D points
//! between consecutive frames, the input of the core estimators.
//!
//! Features come from any [`features::FeatureExtractor`] (SURF as in the paper, or a fast
//! binary detector), so matching and triangulation are written once.
//!
//! | module | what |
//! |---|---|
//! | [`image`] | owned grayscale images, PNG loading, bilinear sampling |
//! | [`orb`] | FAST-9 + Harris ranking + intensity-centroid orientation + steered BRIEF |
//! | [`bucketing`] | strongest features per grid cell |
//! | [`stereo`] | row-constrained stereo matching, sub-pixel disparity, triangulation |
//! | [`temporal`] | mutual nearest neighbours between frames, circular check |
//! | [`frontend`] | two stereo frames to `swarmpose_core::Correspondences` |
//! | [`rectify`] | radial-tangential undistortion and stereo rectification maps, remap |
//! | [`render`] | a tiny renderer of textured planes (tests without data) |
//! | [`draw`] | match drawings (the paper's figure 9) |
//! | [`simd`] | runtime dispatch of the vector kernels (AVX2/POPCNT where the CPU has them) |
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod bucketing;
pub mod draw;
pub mod features;
pub mod frontend;
pub mod image;
pub mod orb;
pub mod rectify;
pub mod render;
pub mod simd;
pub mod stereo;
pub mod surf;
pub mod temporal;
#[cfg(test)]
mod test_noise;
