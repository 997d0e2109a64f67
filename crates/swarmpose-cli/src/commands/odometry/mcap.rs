//! `odometry.mcap` of a run: each frame's result as standard ROS 2 messages
//! ([`swarmpose_ros::write`]), written as the frame is done; the conventions (frames,
//! covariance order, units) are those of [`swarmpose_ros::convert`]. With
//! `--mcap-images N`, frames 0, N, 2N, ... also carry their left image with the inliers
//! drawn and the inliers' points ([`swarmpose_ros::inliers`]).

use nalgebra::Isometry3;
use swarmpose_odometry::FrameResult;
use swarmpose_ros::convert::{FrameNames, pose_in_odom, ros_pose};
use swarmpose_ros::inliers::{inlier_cloud, inlier_image};
use swarmpose_ros::msg::{CameraInfo, Header, Pose, Time};
use swarmpose_ros::result::{OdometryMessages, status};
use swarmpose_ros::write::{FrameMessages, OdometryMcap};
use swarmpose_vision::image::GrayImage;

use super::output::OutputDir;
use crate::error::CliError;

/// The file's name in the output folder.
pub const FILE: &str = "odometry.mcap";

/// The writer of a run's `odometry.mcap`.
pub struct McapOutput {
    writer: OdometryMcap,
    messages: OdometryMessages,
    /// The header stamps of a bag's frames, nanoseconds (`None`: the run's times).
    stamps_ns: Option<Vec<i64>>,
    /// The ground-truth pose of each frame in `odom`, when known.
    ground_truth: Option<Vec<Pose>>,
    /// Every how many frames the image and points are written (0: never).
    images_every: usize,
}

/// A camera pose (first camera's frame) as a ROS pose in `odom`.
fn in_odom(p: &Isometry3<f64>) -> Pose {
    ros_pose(&pose_in_odom(p))
}

fn failure(e: &swarmpose_ros::RosError) -> CliError {
    CliError::failure(e.to_string())
}

impl McapOutput {
    /// Starts `odometry.mcap` in `dir` for frames named `names`, with the image and points
    /// of every `images_every`-th frame (0: none); `camera_info` and `stamps_ns` when the
    /// input is a bag, `ground_truth` (camera poses in the first camera's frame) when known.
    ///
    /// # Errors
    /// Exit status 1 when the file cannot be written.
    pub fn create(
        dir: &OutputDir,
        (names, images_every): (FrameNames, usize),
        camera_info: Option<&CameraInfo>,
        stamps_ns: Option<Vec<i64>>,
        ground_truth: Option<&[Isometry3<f64>]>,
    ) -> Result<Self, CliError> {
        let (file, path) = dir.create(FILE)?;
        let mut writer = OdometryMcap::new(file, &path).map_err(|e| failure(&e))?;
        if let Some(info) = camera_info {
            writer.camera_info(info).map_err(|e| failure(&e))?;
        }
        Ok(Self {
            writer,
            messages: OdometryMessages::new(names),
            stamps_ns,
            ground_truth: ground_truth.map(|g| g.iter().map(in_odom).collect()),
            images_every,
        })
    }

    /// The stamp of frame `i` at `t` seconds: the bag's header stamp, or the run's time.
    fn stamp_ns(&self, i: usize, t: f64) -> i64 {
        self.stamps_ns
            .as_ref()
            .and_then(|s| s.get(i).copied())
            .unwrap_or((t * 1e9).round() as i64)
    }

    /// Writes one frame's messages; `left` reads a frame's left image again when this
    /// frame's image is to be written.
    ///
    /// # Errors
    /// Exit status 1 when the file cannot be written or the image cannot be read again.
    pub fn frame(
        &mut self,
        r: &FrameResult,
        left: &dyn Fn(usize) -> Result<GrayImage, String>,
    ) -> Result<(), CliError> {
        let stamp_ns = self.stamp_ns(r.index, r.timestamp_s);
        let stamp = Time::from_nanos(stamp_ns);
        let (image, points) = if self.images_every > 0 && r.index.is_multiple_of(self.images_every)
        {
            let header = Header {
                stamp,
                frame_id: self.messages.names().camera.clone(),
            };
            let fail = |e: String| {
                CliError::failure(format!("{FILE}: the image of frame {}: {e}", r.index))
            };
            let img = left(r.index).map_err(fail)?;
            let image = inlier_image(r, img.view(), header.clone()).map_err(fail)?;
            (Some(image), Some(inlier_cloud(r, header)))
        } else {
            (None, None)
        };
        let msg = FrameMessages {
            odometry: self.messages.odometry(r, stamp_ns),
            status: status(r, stamp, Vec::new()),
            image,
            points,
            ground_truth: self
                .ground_truth
                .as_ref()
                .and_then(|g| g.get(r.index).copied()),
        };
        self.writer.frame(&msg).map_err(|e| failure(&e))
    }

    /// Writes the paths (with the ground truth when known, a pose per frame) and closes
    /// the file.
    ///
    /// # Errors
    /// Exit status 1 when the file cannot be written.
    pub fn finish(self, ground_truth: Option<&[Isometry3<f64>]>) -> Result<(), CliError> {
        let gt: Option<Vec<_>> = ground_truth.map(|g| g.iter().map(in_odom).collect());
        self.writer.finish(gt.as_deref()).map_err(|e| failure(&e))
    }
}
