//! `odometry.mcap` of a run: each frame's result as standard ROS 2 messages
//! ([`swarmpose_ros::write`]), written as the frame is done; the conventions (frames,
//! covariance order, units) are those of [`swarmpose_ros::convert`].

use nalgebra::Isometry3;
use swarmpose_odometry::{FrameResult, Status};
use swarmpose_ros::convert::{FrameNames, Measurement, odometry, pose_in_odom, ros_pose};
use swarmpose_ros::msg::{
    CameraInfo, DiagnosticArray, DiagnosticStatus, Header, KeyValue, Pose, Time,
};
use swarmpose_ros::write::{FrameMessages, OdometryMcap};

use super::odometry_output::OutputDir;
use crate::error::CliError;

/// The file's name in the output folder.
pub const FILE: &str = "odometry.mcap";

/// The writer of a run's `odometry.mcap`.
pub struct McapOutput {
    writer: OdometryMcap,
    names: FrameNames,
    /// Each frame's time, seconds (for the time since a frame's reference).
    times_s: Vec<f64>,
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

/// The tracking status of a frame as a diagnostic.
fn status(r: &FrameResult, stamp: Time) -> DiagnosticArray {
    let level = match r.status {
        Status::First | Status::Tracked => DiagnosticStatus::OK,
        Status::ConstantVelocity(_) => DiagnosticStatus::WARN,
        Status::Lost(_) => DiagnosticStatus::ERROR,
    };
    let kv = |key: &str, value: String| KeyValue {
        key: key.to_owned(),
        value,
    };
    DiagnosticArray {
        header: Header {
            stamp,
            frame_id: String::new(),
        },
        status: vec![DiagnosticStatus {
            level,
            name: "swarmpose: tracking".to_owned(),
            message: r.status.text(),
            hardware_id: String::new(),
            values: vec![
                kv("frame", r.index.to_string()),
                kv(
                    "reference",
                    r.reference.map_or_else(String::new, |i| i.to_string()),
                ),
                kv("matches", r.counts.matches.to_string()),
                kv("inliers", r.counts.inliers.to_string()),
            ],
        }],
    }
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
            names,
            times_s: Vec::new(),
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
        self.times_s.push(r.timestamp_s);
        let stamp_ns = self.stamp_ns(r.index, r.timestamp_s);
        let measured = r
            .reference
            .filter(|_| r.status.is_tracked())
            .map(|k| Measurement {
                motion: r.measured_motion,
                covariance: r.covariance,
                dt_s: self.times_s.get(k).map_or(0.0, |t0| r.timestamp_s - t0),
            });
        let first = matches!(r.status, Status::First);
        let msg = FrameMessages {
            odometry: odometry(stamp_ns, &r.pose, first, measured.as_ref(), &self.names),
            status: status(r, Time::from_nanos(stamp_ns)),
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
