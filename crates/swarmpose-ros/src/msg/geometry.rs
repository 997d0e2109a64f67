//! `geometry_msgs`, `nav_msgs`, `tf2_msgs`, `diagnostic_msgs`, and the two plain types of
//! the ROS 2 recorder's own test bags (`std_msgs/String`, `rcl_interfaces/Log`).

use serde::{Deserialize, Serialize};

use super::sensor::ros_type;
use super::{Header, RosMessage, Time, fixed};

/// `geometry_msgs/msg/Point`, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Point {
    /// x, metres.
    pub x: f64,
    /// y, metres.
    pub y: f64,
    /// z, metres.
    pub z: f64,
}

/// `geometry_msgs/msg/Vector3`.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Vector3 {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
}

/// `geometry_msgs/msg/Quaternion`, `x y z w` (Hamilton, unit).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Quaternion {
    /// x.
    pub x: f64,
    /// y.
    pub y: f64,
    /// z.
    pub z: f64,
    /// w.
    pub w: f64,
}

/// `geometry_msgs/msg/Pose`: position (metres) and orientation of a frame.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Pose {
    /// Position, metres.
    pub position: Point,
    /// Orientation.
    pub orientation: Quaternion,
}

/// `geometry_msgs/msg/PoseStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseStamped {
    /// Time and the frame the pose is in.
    pub header: Header,
    /// The pose.
    pub pose: Pose,
}
ros_type!(PoseStamped, "geometry_msgs/msg/PoseStamped");

/// `geometry_msgs/msg/PoseWithCovariance`: the covariance is 6x6 row-major over
/// `(x, y, z, rotation about X, rotation about Y, rotation about Z)`, metres and radians.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PoseWithCovariance {
    /// The pose.
    pub pose: Pose,
    /// 6x6 row-major covariance.
    #[serde(with = "fixed")]
    pub covariance: [f64; 36],
}

/// `geometry_msgs/msg/PoseWithCovarianceStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct PoseWithCovarianceStamped {
    /// Time and the frame the pose is in.
    pub header: Header,
    /// The pose and its covariance.
    pub pose: PoseWithCovariance,
}
ros_type!(
    PoseWithCovarianceStamped,
    "geometry_msgs/msg/PoseWithCovarianceStamped"
);

/// `geometry_msgs/msg/Twist`: velocity, metres per second and radians per second.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Twist {
    /// Linear velocity, m/s.
    pub linear: Vector3,
    /// Angular velocity, rad/s.
    pub angular: Vector3,
}

/// `geometry_msgs/msg/TwistWithCovariance`: 6x6 row-major covariance over
/// `(vx, vy, vz, wx, wy, wz)`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct TwistWithCovariance {
    /// The velocity.
    pub twist: Twist,
    /// 6x6 row-major covariance.
    #[serde(with = "fixed")]
    pub covariance: [f64; 36],
}

/// `geometry_msgs/msg/Transform`: `child` frame in the parent frame, metres.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Transform {
    /// Translation, metres.
    pub translation: Vector3,
    /// Rotation.
    pub rotation: Quaternion,
}

/// `geometry_msgs/msg/TransformStamped`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TransformStamped {
    /// Time and the parent frame.
    pub header: Header,
    /// The child frame.
    pub child_frame_id: String,
    /// Pose of the child frame in the parent frame.
    pub transform: Transform,
}

/// `tf2_msgs/msg/TFMessage`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct TfMessage {
    /// The transforms.
    pub transforms: Vec<TransformStamped>,
}
ros_type!(TfMessage, "tf2_msgs/msg/TFMessage");

/// `nav_msgs/msg/Odometry`: pose in `header.frame_id`, twist in `child_frame_id`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Odometry {
    /// Time and the frame of the pose (`odom`).
    pub header: Header,
    /// The frame of the twist (the moving body's).
    pub child_frame_id: String,
    /// Pose and covariance.
    pub pose: PoseWithCovariance,
    /// Velocity and covariance.
    pub twist: TwistWithCovariance,
}
ros_type!(Odometry, "nav_msgs/msg/Odometry");

/// `nav_msgs/msg/Path`.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct Path {
    /// Time and the frame of the poses.
    pub header: Header,
    /// The poses, in order.
    pub poses: Vec<PoseStamped>,
}
ros_type!(Path, "nav_msgs/msg/Path");

/// `diagnostic_msgs/msg/KeyValue`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct KeyValue {
    /// Key.
    pub key: String,
    /// Value.
    pub value: String,
}

/// `diagnostic_msgs/msg/DiagnosticStatus`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct DiagnosticStatus {
    /// 0 OK, 1 WARN, 2 ERROR, 3 STALE.
    pub level: u8,
    /// What is described.
    pub name: String,
    /// The status in words.
    pub message: String,
    /// The device.
    pub hardware_id: String,
    /// Values.
    pub values: Vec<KeyValue>,
}

impl DiagnosticStatus {
    /// Level OK.
    pub const OK: u8 = 0;
    /// Level WARN.
    pub const WARN: u8 = 1;
    /// Level ERROR.
    pub const ERROR: u8 = 2;
}

/// `diagnostic_msgs/msg/DiagnosticArray`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct DiagnosticArray {
    /// Time.
    pub header: Header,
    /// The statuses.
    pub status: Vec<DiagnosticStatus>,
}
ros_type!(DiagnosticArray, "diagnostic_msgs/msg/DiagnosticArray");

/// `std_msgs/msg/String`.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct StringMsg {
    /// The text.
    pub data: String,
}
ros_type!(StringMsg, "std_msgs/msg/String");

/// `rcl_interfaces/msg/Log` (`/rosout`).
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Log {
    /// Time.
    pub stamp: Time,
    /// Level (10 DEBUG to 50 FATAL).
    pub level: u8,
    /// Logger name.
    pub name: String,
    /// The message.
    pub msg: String,
    /// Source file.
    pub file: String,
    /// Function.
    pub function: String,
    /// Line.
    pub line: u32,
}
ros_type!(Log, "rcl_interfaces/msg/Log");

impl Default for PoseWithCovariance {
    fn default() -> Self {
        Self {
            pose: Pose::default(),
            covariance: [0.0; 36],
        }
    }
}

impl Default for TwistWithCovariance {
    fn default() -> Self {
        Self {
            twist: Twist::default(),
            covariance: [0.0; 36],
        }
    }
}
