//! `odometry.mcap` of a run: each frame's result as standard ROS 2 messages
//! ([`swarmpose_ros::write`]), written as the frame is done; the conventions (frames,
//! covariance order, units) are those of [`swarmpose_ros::convert`].

use nalgebra::Isometry3;
use swarmpose_odometry::FrameResult;
use swarmpose_ros::convert::{FrameNames, pose_in_odom, ros_pose};
use swarmpose_ros::msg::{CameraInfo, Pose, Time};
use swarmpose_ros::result::{OdometryMessages, status};
use swarmpose_ros::write::{FrameMessages, OdometryMcap};

use super::odometry_output::OutputDir;
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
}

/// A camera pose (first camera's frame) as a ROS pose in `odom`.
fn in_odom(p: &Isometry3<f64>) -> Pose {
    ros_pose(&pose_in_odom(p))
}

fn failure(e: &swarmpose_ros::RosError) -> CliError {
    CliError::failure(e.to_string())
}

impl McapOutput {
    /// Starts `odometry.mcap` in `dir`; `camera_info` and `stamps_ns` when the input is a
    /// bag, `ground_truth` (camera poses in the first camera's frame) when known.
    ///
    /// # Errors
    /// Exit status 1 when the file cannot be written.
    pub fn create(
        dir: &OutputDir,
        names: FrameNames,
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
        })
    }

    /// The stamp of frame `i` at `t` seconds: the bag's header stamp, or the run's time.
    fn stamp_ns(&self, i: usize, t: f64) -> i64 {
        self.stamps_ns
            .as_ref()
            .and_then(|s| s.get(i).copied())
            .unwrap_or((t * 1e9).round() as i64)
    }

    /// Writes one frame's messages.
    ///
    /// # Errors
    /// Exit status 1 when the file cannot be written.
    pub fn frame(&mut self, r: &FrameResult) -> Result<(), CliError> {
        let stamp_ns = self.stamp_ns(r.index, r.timestamp_s);
        let msg = FrameMessages {
            odometry: self.messages.odometry(r, stamp_ns),
            status: status(r, Time::from_nanos(stamp_ns), Vec::new()),
            image: None,
            points: None,
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
