//! # swarmpose-odometry
//!
//! Stereo visual odometry (work in progress).
#![deny(missing_docs)]
