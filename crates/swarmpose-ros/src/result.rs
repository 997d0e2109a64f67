//! An engine's [`FrameResult`] as the ROS 2 messages of a frame: `nav_msgs/Odometry`
//! ([`crate::convert`]'s conventions) and the tracking status, a
//! `diagnostic_msgs/DiagnosticArray`. One place for `odometry.mcap` and the live node.
//!
//! The status has one `DiagnosticStatus` named [`STATUS_NAME`]: level OK for a first or
//! tracked frame, WARN for a frame held at constant velocity, ERROR for a lost one; its
//! message is the engine's status text; its values are `frame`, `reference` (the frame
//! the motion was measured from, empty for none), `matches`, `inliers`, then any the
//! caller adds (the node adds its drop counts).

use swarmpose_odometry::{FrameResult, Status};

use crate::convert::{FrameNames, Measurement, odometry};
use crate::msg::{
    DiagnosticArray, DiagnosticStatus, Header, KeyValue, Odometry, TfMessage, Time, Transform,
    TransformStamped, Vector3,
};

/// The name of the tracking status.
pub const STATUS_NAME: &str = "swarmpose: tracking";

/// A key and value of a status.
#[must_use]
pub fn key_value(key: &str, value: impl ToString) -> KeyValue {
    KeyValue {
        key: key.to_owned(),
        value: value.to_string(),
    }
}

/// A status array of one status at `stamp`.
#[must_use]
pub fn status_array(
    stamp: Time,
    level: u8,
    message: String,
    values: Vec<KeyValue>,
) -> DiagnosticArray {
    DiagnosticArray {
        header: Header {
            stamp,
            frame_id: String::new(),
        },
        status: vec![DiagnosticStatus {
            level,
            name: STATUS_NAME.to_owned(),
            message,
            hardware_id: String::new(),
            values,
        }],
    }
}

/// The tracking status of a frame, with `extra` values after the usual ones.
#[must_use]
pub fn status(r: &FrameResult, stamp: Time, extra: Vec<KeyValue>) -> DiagnosticArray {
    let level = match r.status {
        Status::First | Status::Tracked => DiagnosticStatus::OK,
        Status::ConstantVelocity(_) => DiagnosticStatus::WARN,
        Status::Lost(_) => DiagnosticStatus::ERROR,
    };
    let mut values = vec![
        key_value("frame", r.index),
        key_value(
            "reference",
            r.reference.map_or_else(String::new, |i| i.to_string()),
        ),
        key_value("matches", r.counts.matches),
        key_value("inliers", r.counts.inliers),
    ];
    values.extend(extra);
    status_array(stamp, level, r.status.text(), values)
}

/// Turns a run's results into `nav_msgs/Odometry`, frame after frame: it keeps each
/// frame's time (8 bytes a frame) for the time since a frame's reference frame.
#[derive(Debug, Clone, Default)]
pub struct OdometryMessages {
    names: FrameNames,
    /// Each frame's time, seconds, by the engine's frame index.
    times_s: Vec<f64>,
}

impl OdometryMessages {
    /// For frames named `names`.
    #[must_use]
    pub fn new(names: FrameNames) -> Self {
        Self {
            names,
            times_s: Vec::new(),
        }
    }

    /// The frame names.
    #[must_use]
    pub fn names(&self) -> &FrameNames {
        &self.names
    }

    /// The `nav_msgs/Odometry` of `r` (the next result of the run), stamped `stamp_ns`.
    pub fn odometry(&mut self, r: &FrameResult, stamp_ns: i64) -> Odometry {
        self.times_s.push(r.timestamp_s);
        let measured = r
            .reference
            .filter(|_| r.status.is_tracked())
            .map(|k| Measurement {
                motion: r.measured_motion,
                covariance: r.covariance,
                dt_s: self.times_s.get(k).map_or(0.0, |t0| r.timestamp_s - t0),
            });
        let first = matches!(r.status, Status::First);
        odometry(stamp_ns, &r.pose, first, measured.as_ref(), &self.names)
    }
}

/// The `/tf` message of an odometry: its child frame (the camera) in its frame (`odom`).
#[must_use]
pub fn tf_of(o: &Odometry) -> TfMessage {
    let p = o.pose.pose;
    TfMessage {
        transforms: vec![TransformStamped {
            header: o.header.clone(),
            child_frame_id: o.child_frame_id.clone(),
            transform: Transform {
                translation: Vector3 {
                    x: p.position.x,
                    y: p.position.y,
                    z: p.position.z,
                },
                rotation: p.orientation,
            },
        }],
    }
}
