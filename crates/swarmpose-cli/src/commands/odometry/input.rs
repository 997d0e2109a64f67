//! The input of `swarmpose odometry`, one front door for the command line and for Python
//! (`swarmpose.odometry`, `swarmpose.Sequence`): a TUM RGB-D folder
//! ([`swarmpose_runs::rgbd::RgbdSequence`]), or else what [`swarmpose_ros::open_input`]
//! opens: a ROS 2 bag (stereo or RGB-D) or a stereo dataset folder.

use std::path::Path;

use swarmpose_ros::{Input, OpenedInput, StereoOptions, is_bag};
use swarmpose_runs::RunError;
use swarmpose_runs::rgbd::{RgbdSequence, detect};

/// Opens `path`: a TUM RGB-D folder (`rgb.txt` and `depth.txt`; no topics may be named
/// in `opts`), else a ROS 2 bag with `opts` or a stereo dataset folder.
///
/// # Errors
/// The TUM reader's error, or [`swarmpose_ros::open_input`]'s (as
/// [`RunError::Dataset`]): one line naming the input.
pub fn open_input(path: &Path, opts: &StereoOptions) -> Result<OpenedInput, RunError> {
    let named = opts.left.is_some() || opts.right.is_some() || opts.depth.is_some();
    if !named && !is_bag(path) && detect(path) {
        return Ok(OpenedInput {
            input: Input::Rgbd(Box::new(RgbdSequence::open(path)?)),
            bag: None,
        });
    }
    Ok(swarmpose_ros::open_input(path, opts)?)
}
