//! RGB-D sequences behind one [`DepthSequence`] abstraction, as [`crate::StereoSequence`]
//! is for stereo: frames in order as a gray image and the depth of each of its pixels,
//! the colour camera's pinhole intrinsics, optional ground truth. The TUM RGB-D folder
//! reader (`swarmpose_runs::rgbd`) and the ROS 2 bag reader (`swarmpose_ros::rgbd`)
//! implement it, and one run loop (`swarmpose_runs::batch::run_rgbd_sequence`) serves both.

use std::path::Path;

use nalgebra::Isometry3;
use swarmpose_vision::image::GrayImage;

use crate::DatasetError;

/// Pinhole intrinsics of an undistorted camera, pixels.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Intrinsics {
    /// Focal length along x.
    pub fx: f64,
    /// Focal length along y.
    pub fy: f64,
    /// Principal point column.
    pub cx: f64,
    /// Principal point row.
    pub cy: f64,
}

impl Default for Intrinsics {
    /// TUM's recommendation for its sequences as published: 525, 525, 319.5, 239.5.
    fn default() -> Self {
        Self {
            fx: 525.0,
            fy: 525.0,
            cx: 319.5,
            cy: 239.5,
        }
    }
}

impl Intrinsics {
    /// Why these are not a plausible camera for `width` x `height` images (the focal
    /// lengths and principal point checks of [`crate::RectifiedStereo::implausibility`]),
    /// or `None`.
    #[must_use]
    pub fn implausibility(&self, width: usize, height: usize) -> Option<String> {
        crate::RectifiedStereo {
            fx: self.fx,
            fy: self.fy,
            cx: self.cx,
            cy: self.cy,
            baseline_m: 1.0,
        }
        .implausibility(width, height)
    }
}

/// One RGB-D frame: the gray image and, row-major, the depth of each of its pixels along
/// the camera's optical axis (z), metres, 0 where there is none.
#[derive(Debug, Clone, PartialEq)]
pub struct RgbdFrame {
    /// The colour image as 8-bit gray.
    pub gray: GrayImage,
    /// Depth, metres, `gray.width * gray.height` values (0: no depth).
    pub depth_m: Vec<f32>,
}

/// An RGB-D sequence: frames in order, the colour camera, optional ground truth.
pub trait DepthSequence: Send + Sync {
    /// The layout (`tum rgb-d`, `ros2 bag`).
    fn layout(&self) -> &'static str;

    /// The sequence's directory or bag.
    fn root(&self) -> &Path;

    /// Number of frames.
    fn len(&self) -> usize;

    /// True when there are no frames.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// The colour camera's intrinsics and the images' width and height (pixels),
    /// checked to be a plausible camera for the images.
    ///
    /// # Errors
    /// A first image that cannot be read, or intrinsics that are not plausible (the
    /// message names where they come from).
    fn camera(&self) -> Result<(Intrinsics, (usize, usize)), DatasetError>;

    /// Loads frame `i` (0-based).
    ///
    /// # Errors
    /// A missing or unreadable image, a depth image that is not one or not of the colour
    /// image's size, or `i` out of range; the message names the file (or topic).
    fn frame(&self, i: usize) -> Result<RgbdFrame, DatasetError>;

    /// Warnings found when the sequence was opened, one line each.
    fn notes(&self) -> &[String] {
        &[]
    }

    /// Ground-truth pose of the colour camera at each frame, in its frame at frame 0.
    fn ground_truth(&self) -> Option<&[Isometry3<f64>]>;

    /// Time of frame `i`, seconds, on the sequence's own clock (only differences matter);
    /// `None` for `i` out of range.
    fn timestamp_s(&self, i: usize) -> Option<f64>;
}
