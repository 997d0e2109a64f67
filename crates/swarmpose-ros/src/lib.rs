//! # swarmpose-ros
//!
//! ROS 2 without a ROS install: the message types swarmpose reads and writes ([`msg`],
//! CDR through `cdr-encoding`), ROS 2 bags ([`bag`]: MCAP through the `mcap` crate,
//! SQLite `.db3` through `rusqlite`, rosbag2 folders with split files), stereo frames
//! from a bag ([`stereo`]), RGB-D frames from a bag ([`rgbd`]), the `odometry.mcap` writer ([`mod@write`]), and an engine's
//! results as messages ([`result`], and its inliers: [`inliers`]).
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod bag;
pub mod convert;
pub mod error;
pub mod image;
pub mod inliers;
pub mod msg;
pub mod result;
pub mod rgbd;
pub mod source;
pub mod stereo;
pub mod write;

pub use bag::{Bag, Topic};
pub use error::{CdrError, RosError};
pub use rgbd::BagRgbdSequence;
pub use source::{Input, OpenedInput, is_bag, open_input};
pub use stereo::frames::BagInfo;
pub use stereo::{BagSequence, StereoOptions};
