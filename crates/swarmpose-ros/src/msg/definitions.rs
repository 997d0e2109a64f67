//! The `.msg` definitions of the types in [`super`] (comments and constants dropped but
//! those of the status levels), and their `ros2msg` schema texts: the type's definition,
//! then each type it uses once, after a line of 80 `=` and `MSG: pkg/Name`, the way
//! rosbag2 writes them.

/// `(type, definition)` of every type swarmpose writes or reads, `pkg/msg/Name`. Field
/// types outside the built-in ones are written `pkg/Name`.
const DEFINITIONS: &[(&str, &str)] = &[
    ("builtin_interfaces/msg/Time", "int32 sec\nuint32 nanosec\n"),
    (
        "std_msgs/msg/Header",
        "builtin_interfaces/Time stamp\nstring frame_id\n",
    ),
    ("std_msgs/msg/String", "string data\n"),
    (
        "sensor_msgs/msg/Image",
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring encoding\n\
         uint8 is_bigendian\nuint32 step\nuint8[] data\n",
    ),
    (
        "sensor_msgs/msg/CompressedImage",
        "std_msgs/Header header\nstring format\nuint8[] data\n",
    ),
    (
        "sensor_msgs/msg/RegionOfInterest",
        "uint32 x_offset\nuint32 y_offset\nuint32 height\nuint32 width\nbool do_rectify\n",
    ),
    (
        "sensor_msgs/msg/CameraInfo",
        "std_msgs/Header header\nuint32 height\nuint32 width\nstring distortion_model\n\
         float64[] d\nfloat64[9] k\nfloat64[9] r\nfloat64[12] p\nuint32 binning_x\n\
         uint32 binning_y\nsensor_msgs/RegionOfInterest roi\n",
    ),
    (
        "sensor_msgs/msg/PointField",
        "uint8 INT8=1\nuint8 UINT8=2\nuint8 INT16=3\nuint8 UINT16=4\nuint8 INT32=5\n\
         uint8 UINT32=6\nuint8 FLOAT32=7\nuint8 FLOAT64=8\nstring name\nuint32 offset\n\
         uint8 datatype\nuint32 count\n",
    ),
    (
        "sensor_msgs/msg/PointCloud2",
        "std_msgs/Header header\nuint32 height\nuint32 width\n\
         sensor_msgs/PointField[] fields\nbool is_bigendian\nuint32 point_step\n\
         uint32 row_step\nuint8[] data\nbool is_dense\n",
    ),
    (
        "geometry_msgs/msg/Point",
        "float64 x\nfloat64 y\nfloat64 z\n",
    ),
    (
        "geometry_msgs/msg/Vector3",
        "float64 x\nfloat64 y\nfloat64 z\n",
    ),
    (
        "geometry_msgs/msg/Quaternion",
        "float64 x 0\nfloat64 y 0\nfloat64 z 0\nfloat64 w 1\n",
    ),
    (
        "geometry_msgs/msg/Pose",
        "geometry_msgs/Point position\ngeometry_msgs/Quaternion orientation\n",
    ),
    (
        "geometry_msgs/msg/PoseStamped",
        "std_msgs/Header header\ngeometry_msgs/Pose pose\n",
    ),
    (
        "geometry_msgs/msg/PoseWithCovariance",
        "geometry_msgs/Pose pose\nfloat64[36] covariance\n",
    ),
    (
        "geometry_msgs/msg/PoseWithCovarianceStamped",
        "std_msgs/Header header\ngeometry_msgs/PoseWithCovariance pose\n",
    ),
    (
        "geometry_msgs/msg/Twist",
        "geometry_msgs/Vector3 linear\ngeometry_msgs/Vector3 angular\n",
    ),
    (
        "geometry_msgs/msg/TwistWithCovariance",
        "geometry_msgs/Twist twist\nfloat64[36] covariance\n",
    ),
    (
        "geometry_msgs/msg/Transform",
        "geometry_msgs/Vector3 translation\ngeometry_msgs/Quaternion rotation\n",
    ),
    (
        "geometry_msgs/msg/TransformStamped",
        "std_msgs/Header header\nstring child_frame_id\ngeometry_msgs/Transform transform\n",
    ),
    (
        "tf2_msgs/msg/TFMessage",
        "geometry_msgs/TransformStamped[] transforms\n",
    ),
    (
        "nav_msgs/msg/Odometry",
        "std_msgs/Header header\nstring child_frame_id\n\
         geometry_msgs/PoseWithCovariance pose\ngeometry_msgs/TwistWithCovariance twist\n",
    ),
    (
        "nav_msgs/msg/Path",
        "std_msgs/Header header\ngeometry_msgs/PoseStamped[] poses\n",
    ),
    ("diagnostic_msgs/msg/KeyValue", "string key\nstring value\n"),
    (
        "diagnostic_msgs/msg/DiagnosticStatus",
        "byte OK=0\nbyte WARN=1\nbyte ERROR=2\nbyte STALE=3\nbyte level\nstring name\n\
         string message\nstring hardware_id\ndiagnostic_msgs/KeyValue[] values\n",
    ),
    (
        "diagnostic_msgs/msg/DiagnosticArray",
        "std_msgs/Header header\ndiagnostic_msgs/DiagnosticStatus[] status\n",
    ),
    (
        "rcl_interfaces/msg/Log",
        "byte DEBUG=10\nbyte INFO=20\nbyte WARN=30\nbyte ERROR=40\nbyte FATAL=50\n\
         builtin_interfaces/Time stamp\nuint8 level\nstring name\nstring msg\nstring file\n\
         string function\nuint32 line\n",
    ),
];

/// The `.msg` definition of `msg_type` (`pkg/msg/Name` or `pkg/Name`), without the types
/// it uses; `None` for a type swarmpose does not know.
#[must_use]
pub fn definition_of(msg_type: &str) -> Option<&'static str> {
    let full = full_name(msg_type);
    DEFINITIONS
        .iter()
        .find(|(name, _)| *name == full)
        .map(|(_, def)| *def)
}

/// `pkg/msg/Name` of `pkg/Name` (unchanged when already full).
fn full_name(msg_type: &str) -> String {
    match msg_type.split('/').collect::<Vec<_>>()[..] {
        [pkg, name] => format!("{pkg}/msg/{name}"),
        _ => msg_type.to_owned(),
    }
}

/// The message types a definition's fields use (`pkg/Name`, arrays stripped), in order.
fn used_types(definition: &str) -> Vec<&str> {
    definition
        .lines()
        .filter_map(|line| {
            let ty = line.split_whitespace().next()?;
            let ty = ty.split('[').next()?;
            ty.contains('/').then_some(ty)
        })
        .collect()
}

/// The `ros2msg` schema of `msg_type`: its definition, then that of every type it uses
/// (depth first, each once) under `MSG: pkg/Name`. `None` for an unknown type.
#[must_use]
pub fn schema_text(msg_type: &str) -> Option<String> {
    let mut text = definition_of(msg_type)?.to_owned();
    let mut seen: Vec<String> = Vec::new();
    let mut stack: Vec<String> = used_types(definition_of(msg_type)?)
        .into_iter()
        .rev()
        .map(str::to_owned)
        .collect();
    while let Some(ty) = stack.pop() {
        if seen.contains(&ty) {
            continue;
        }
        let def = definition_of(&ty)?;
        text.push_str(&"=".repeat(80));
        text.push_str(&format!("\nMSG: {ty}\n{def}"));
        stack.extend(used_types(def).into_iter().rev().map(str::to_owned));
        seen.push(ty);
    }
    Some(text)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_used_type_is_defined() {
        for (name, def) in DEFINITIONS {
            for ty in used_types(def) {
                assert!(definition_of(ty).is_some(), "{name} uses {ty}: undefined");
            }
            assert!(schema_text(name).is_some(), "{name}");
        }
    }

    #[test]
    fn odometry_schema_lists_each_type_once() {
        let s = schema_text("nav_msgs/msg/Odometry").expect("known");
        assert!(s.starts_with("std_msgs/Header header\n"), "{s}");
        for ty in [
            "std_msgs/Header",
            "builtin_interfaces/Time",
            "geometry_msgs/PoseWithCovariance",
            "geometry_msgs/Pose",
            "geometry_msgs/Point",
            "geometry_msgs/Quaternion",
            "geometry_msgs/TwistWithCovariance",
            "geometry_msgs/Twist",
            "geometry_msgs/Vector3",
        ] {
            assert_eq!(s.matches(&format!("MSG: {ty}\n")).count(), 1, "{ty} in {s}");
        }
        assert!(schema_text("nav_msgs/msg/Unknown").is_none());
    }
}
