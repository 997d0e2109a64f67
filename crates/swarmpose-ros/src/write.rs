//! `odometry.mcap`: a run's result as standard ROS 2 messages in an MCAP file (profile
//! `ros2`, `ros2msg` schemas, CDR), written frame by frame: each frame's messages are
//! one zstd chunk, flushed at once, so a killed run leaves a file that MCAP readers read
//! up to its last whole frame; [`OdometryMcap::finish`] adds the paths and the summary.
//!
//! Topics (names in [`Topics`]): `nav_msgs/Odometry`, `geometry_msgs/PoseWithCovarianceStamped`,
//! `tf2_msgs/TFMessage` (`/tf`), `diagnostic_msgs/DiagnosticArray`, the left
//! `sensor_msgs/CameraInfo`, the ground truth's `geometry_msgs/PoseStamped` when known
//! (one per frame, so that `evo_ape bag2 odometry.mcap` compares the two topics), and at
//! the end `nav_msgs/Path` of the estimate and, when
//! known, of the ground truth; optionally `sensor_msgs/CompressedImage` (PNG) and
//! `sensor_msgs/PointCloud2`.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::BufWriter;
use std::path::{Path as FsPath, PathBuf};

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions, Writer};

use crate::error::RosError;
use crate::msg::{
    CameraInfo, CompressedImage, DiagnosticArray, Header, Odometry, Path, PointCloud2, Pose,
    PoseStamped, PoseWithCovarianceStamped, RosMessage, TfMessage, Time, encode, schema_text,
};

/// The topic names of `odometry.mcap`, in one place.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Topics;

impl Topics {
    /// `nav_msgs/Odometry`, one per frame.
    pub const ODOMETRY: &'static str = "/swarmpose/odometry";
    /// `geometry_msgs/PoseWithCovarianceStamped`, one per frame.
    pub const POSE: &'static str = "/swarmpose/pose";
    /// `tf2_msgs/TFMessage`, one per frame.
    pub const TF: &'static str = "/tf";
    /// `diagnostic_msgs/DiagnosticArray`, one per frame.
    pub const STATUS: &'static str = "/swarmpose/status";
    /// `sensor_msgs/CameraInfo` of the left camera, once.
    pub const CAMERA_INFO: &'static str = "/swarmpose/camera_info";
    /// `nav_msgs/Path` of the estimate, at the end.
    pub const PATH: &'static str = "/swarmpose/path";
    /// `nav_msgs/Path` of the ground truth, at the end.
    pub const GROUND_TRUTH: &'static str = "/swarmpose/ground_truth";
    /// `geometry_msgs/PoseStamped` of the ground truth, one per frame when known.
    pub const GROUND_TRUTH_POSE: &'static str = "/swarmpose/ground_truth/pose";
    /// `sensor_msgs/CompressedImage` (PNG) of the left image with the inliers.
    pub const IMAGE: &'static str = "/swarmpose/image/compressed";
    /// `sensor_msgs/PointCloud2` of the inlier points.
    pub const POINTS: &'static str = "/swarmpose/points";
}

/// One frame's messages.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameMessages {
    /// The odometry (pose, twist, covariances).
    pub odometry: Odometry,
    /// The tracking status.
    pub status: DiagnosticArray,
    /// The left image with the inliers drawn, when asked for.
    pub image: Option<CompressedImage>,
    /// The inlier points, when asked for.
    pub points: Option<PointCloud2>,
    /// The ground-truth pose of the camera (in the estimate's frame), when known.
    pub ground_truth: Option<Pose>,
}

/// The `odometry.mcap` writer.
pub struct OdometryMcap {
    path: PathBuf,
    writer: Writer<BufWriter<File>>,
    channels: BTreeMap<&'static str, u16>,
    sequence: u32,
    poses: Vec<PoseStamped>,
    last_stamp: Time,
}

impl std::fmt::Debug for OdometryMcap {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("OdometryMcap")
            .field("path", &self.path)
            .field("frames", &self.poses.len())
            .finish_non_exhaustive()
    }
}

/// The channels: topic and type.
const CHANNELS: &[(&str, &str)] = &[
    (Topics::ODOMETRY, Odometry::TYPE),
    (Topics::POSE, PoseWithCovarianceStamped::TYPE),
    (Topics::TF, TfMessage::TYPE),
    (Topics::STATUS, DiagnosticArray::TYPE),
    (Topics::CAMERA_INFO, CameraInfo::TYPE),
    (Topics::PATH, Path::TYPE),
    (Topics::GROUND_TRUTH, Path::TYPE),
    (Topics::GROUND_TRUTH_POSE, PoseStamped::TYPE),
    (Topics::IMAGE, CompressedImage::TYPE),
    (Topics::POINTS, PointCloud2::TYPE),
];

impl OdometryMcap {
    /// Starts `odometry.mcap` in `file` (already created at `path`; messages name it).
    ///
    /// # Errors
    /// [`RosError::Write`].
    pub fn new(file: File, path: &FsPath) -> Result<Self, RosError> {
        let werr = |e: &dyn std::fmt::Display| RosError::Write {
            path: path.to_owned(),
            message: e.to_string(),
        };
        let mut writer = WriteOptions::new()
            .profile("ros2")
            .library(concat!("swarmpose ", env!("CARGO_PKG_VERSION")))
            .compression(Some(Compression::Zstd))
            .create(BufWriter::new(file))
            .map_err(|e| werr(&e))?;
        let mut channels = BTreeMap::new();
        let mut schemas: BTreeMap<&str, u16> = BTreeMap::new();
        for &(topic, ty) in CHANNELS {
            let schema = match schemas.get(ty) {
                Some(&id) => id,
                None => {
                    let text =
                        schema_text(ty).ok_or_else(|| werr(&format!("no schema for {ty}")))?;
                    let id = writer
                        .add_schema(ty, "ros2msg", text.as_bytes())
                        .map_err(|e| werr(&e))?;
                    schemas.insert(ty, id);
                    id
                }
            };
            let id = writer
                .add_channel(schema, topic, "cdr", &BTreeMap::new())
                .map_err(|e| werr(&e))?;
            channels.insert(topic, id);
        }
        Ok(Self {
            path: path.to_owned(),
            writer,
            channels,
            sequence: 0,
            poses: Vec::new(),
            last_stamp: Time::default(),
        })
    }

    fn write<T: RosMessage>(
        &mut self,
        topic: &'static str,
        stamp: Time,
        msg: &T,
    ) -> Result<(), RosError> {
        let werr = |message: String| RosError::Write {
            path: self.path.clone(),
            message,
        };
        let channel_id = *self
            .channels
            .get(topic)
            .ok_or_else(|| werr(format!("no channel {topic}")))?;
        let data = encode(msg).map_err(|e| werr(e.0))?;
        let t = u64::try_from(stamp.as_nanos()).unwrap_or(0);
        self.sequence = self.sequence.wrapping_add(1);
        self.writer
            .write_to_known_channel(
                &MessageHeader {
                    channel_id,
                    sequence: self.sequence,
                    log_time: t,
                    publish_time: t,
                },
                &data,
            )
            .map_err(|e| werr(e.to_string()))
    }

    /// Writes the left camera's `CameraInfo`.
    ///
    /// # Errors
    /// [`RosError::Write`].
    pub fn camera_info(&mut self, info: &CameraInfo) -> Result<(), RosError> {
        self.write(Topics::CAMERA_INFO, info.header.stamp, info)
    }

    /// Writes one frame (odometry, pose, tf, status, and the image, points and ground
    /// truth when given) and flushes it to the file as one chunk.
    ///
    /// # Errors
    /// [`RosError::Write`].
    pub fn frame(&mut self, f: &FrameMessages) -> Result<(), RosError> {
        let o = &f.odometry;
        let stamp = o.header.stamp;
        self.write(Topics::ODOMETRY, stamp, o)?;
        let pose = PoseWithCovarianceStamped {
            header: o.header.clone(),
            pose: o.pose,
        };
        self.write(Topics::POSE, stamp, &pose)?;
        let p = o.pose.pose;
        self.write(Topics::TF, stamp, &crate::result::tf_of(o))?;
        self.write(Topics::STATUS, stamp, &f.status)?;
        if let Some(img) = &f.image {
            self.write(Topics::IMAGE, stamp, img)?;
        }
        if let Some(points) = &f.points {
            self.write(Topics::POINTS, stamp, points)?;
        }
        if let Some(truth) = f.ground_truth {
            let truth = PoseStamped {
                header: o.header.clone(),
                pose: truth,
            };
            self.write(Topics::GROUND_TRUTH_POSE, stamp, &truth)?;
        }
        self.poses.push(PoseStamped {
            header: o.header.clone(),
            pose: p,
        });
        self.last_stamp = stamp;
        self.writer.flush().map_err(|e| RosError::Write {
            path: self.path.clone(),
            message: e.to_string(),
        })
    }

    /// Writes the paths (the estimate, and the ground truth when given: poses in the
    /// same frame as the estimate, one per frame) and the summary, and closes the file.
    ///
    /// # Errors
    /// [`RosError::Write`].
    pub fn finish(mut self, ground_truth: Option<&[Pose]>) -> Result<(), RosError> {
        if let Some(first) = self.poses.first() {
            let header = Header {
                stamp: self.last_stamp,
                frame_id: first.header.frame_id.clone(),
            };
            let path = Path {
                header: header.clone(),
                poses: std::mem::take(&mut self.poses),
            };
            self.write(Topics::PATH, header.stamp, &path)?;
            if let Some(gt) = ground_truth {
                let truth = Path {
                    header: header.clone(),
                    poses: path
                        .poses
                        .iter()
                        .zip(gt)
                        .map(|(p, g)| PoseStamped {
                            header: p.header.clone(),
                            pose: *g,
                        })
                        .collect(),
                };
                self.write(Topics::GROUND_TRUTH, header.stamp, &truth)?;
            }
        }
        self.writer.finish().map_err(|e| RosError::Write {
            path: self.path.clone(),
            message: e.to_string(),
        })?;
        Ok(())
    }
}
