"""The ROS 2 message types the node reads and writes, as Eclipse Cyclone DDS Python IDL
types with ROS 2's DDS names (`pkg::msg::dds_::Name_`, final extensibility, XCDR1 as
rmw_cyclonedds_cpp writes them). Topic names on the wire carry ROS 2's `rt` prefix."""

import types
from dataclasses import dataclass

import cyclonedds.idl.types as t
from cyclonedds.idl import IdlStruct
from cyclonedds.idl._machinery import BytesMachine


def dds_topic(ros_topic: str) -> str:
    """`/a/b` -> `rt/a/b`, as ROS 2 names its DDS topics."""
    return "rt" + ros_topic if ros_topic.startswith("/") else "rt/" + ros_topic


# The messages, in the order they refer to each other: `package/Name: type field, ...`, in
# wire order, with ROS 2's primitive names (`T[]` a sequence, `T[n]` an array).
_MESSAGES = """
builtin_interfaces/Time: int32 sec, uint32 nanosec
std_msgs/Header: Time stamp, string frame_id
sensor_msgs/Image: Header header, uint32 height, uint32 width, string encoding,
    uint8 is_bigendian, uint32 step, uint8[] data
sensor_msgs/RegionOfInterest: uint32 x_offset, uint32 y_offset, uint32 height, uint32 width,
    bool do_rectify
sensor_msgs/CameraInfo: Header header, uint32 height, uint32 width, string distortion_model,
    float64[] d, float64[9] k, float64[9] r, float64[12] p, uint32 binning_x,
    uint32 binning_y, RegionOfInterest roi
geometry_msgs/Point: float64 x, float64 y, float64 z
geometry_msgs/Vector3: float64 x, float64 y, float64 z
geometry_msgs/Quaternion: float64 x, float64 y, float64 z, float64 w
geometry_msgs/Pose: Point position, Quaternion orientation
geometry_msgs/PoseWithCovariance: Pose pose, float64[36] covariance
geometry_msgs/Twist: Vector3 linear, Vector3 angular
geometry_msgs/TwistWithCovariance: Twist twist, float64[36] covariance
nav_msgs/Odometry: Header header, string child_frame_id, PoseWithCovariance pose,
    TwistWithCovariance twist
geometry_msgs/PoseStamped: Header header, Pose pose
nav_msgs/Path: Header header, PoseStamped[] poses
geometry_msgs/Transform: Vector3 translation, Quaternion rotation
geometry_msgs/TransformStamped: Header header, string child_frame_id, Transform transform
tf2_msgs/TFMessage: TransformStamped[] transforms
diagnostic_msgs/KeyValue: string key, string value
diagnostic_msgs/DiagnosticStatus: uint8 level, string name, string message,
    string hardware_id, KeyValue[] values
diagnostic_msgs/DiagnosticArray: Header header, DiagnosticStatus[] status
"""

_PRIMITIVES = {
    "bool": bool,
    "string": str,
    "int32": t.int32,
    "uint8": t.uint8,
    "uint32": t.uint32,
    "float64": t.float64,
}


def _field_type(name: str, known: dict):
    """The IDL type of a field type of the table: a primitive, a message defined above it,
    `T[]` or `T[n]`."""
    if name.endswith("[]"):
        return t.sequence[_field_type(name[:-2], known)]
    if name.endswith("]"):
        inner, n = name[:-1].split("[")
        return t.array[_field_type(inner, known), int(n)]
    return _PRIMITIVES.get(name) or known[name]


def _message(package: str, name: str, fields: dict) -> type:
    """`@dataclass class Name(IdlStruct, typename="package::msg::dds_::Name_")` with
    `fields` (name to IDL type, in wire order)."""

    def body(namespace: dict) -> None:
        namespace.update(__annotations__=fields, __module__=__name__, __qualname__=name)

    typename = f"{package}::msg::dds_::{name}_"
    return dataclass(types.new_class(name, (IdlStruct,), {"typename": typename}, body))


def _define_messages() -> dict:
    """The classes of `_MESSAGES`, by name."""
    known = {}
    for line in _MESSAGES.replace(",\n", ", ").strip().splitlines():
        head, spec = line.split(":", 1)
        package, name = head.split("/")
        pairs = (f.split() for f in spec.split(","))
        fields = {field: _field_type(kind, known) for kind, field in pairs}
        known[name] = _message(package, name, fields)
    return known


globals().update(_define_messages())


def _bytes_as_one_block(cls, field: str):
    """`sequence<uint8>` `field` of `cls` (de)serialised from and to `bytes` in one block
    (the same bytes on the wire: a 4-byte length, then the octets) instead of one Python
    call per byte (80 ms for a 1241x376 image)."""
    cls.__idl__.populate()
    for machine in (cls.__idl__.v1_machine, cls.__idl__.v2_machine):
        machine.members_machines[field] = BytesMachine()


_bytes_as_one_block(Image, "data")
