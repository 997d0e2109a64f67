//! `sensor_msgs`: images, compressed images, camera calibration, point clouds.

use serde::{Deserialize, Serialize};

use super::{Header, RosMessage, fixed};

macro_rules! ros_type {
    ($t:ty, $name:literal) => {
        impl RosMessage for $t {
            const TYPE: &'static str = $name;
        }
    };
}
pub(crate) use ros_type;

/// `sensor_msgs/msg/Image`: uncompressed pixels, rows of `step` bytes.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Image {
    /// Time of capture and the camera's optical frame.
    pub header: Header,
    /// Rows, pixels.
    pub height: u32,
    /// Columns, pixels.
    pub width: u32,
    /// Pixel encoding (`mono8`, `rgb8`, `16UC1`, ...).
    pub encoding: String,
    /// 1 when multi-byte values are big-endian.
    pub is_bigendian: u8,
    /// Bytes per row.
    pub step: u32,
    /// `step * height` bytes.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}
ros_type!(Image, "sensor_msgs/msg/Image");

/// `sensor_msgs/msg/CompressedImage`: a PNG or JPEG file's bytes.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct CompressedImage {
    /// Time of capture and the camera's optical frame.
    pub header: Header,
    /// `png`, `jpeg`, or image_transport's `ENCODING; png compressed ...`.
    pub format: String,
    /// The compressed file.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
}
ros_type!(CompressedImage, "sensor_msgs/msg/CompressedImage");

/// `sensor_msgs/msg/RegionOfInterest`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct RegionOfInterest {
    /// Left column, pixels.
    pub x_offset: u32,
    /// Top row, pixels.
    pub y_offset: u32,
    /// Rows, pixels (0: the whole image).
    pub height: u32,
    /// Columns, pixels (0: the whole image).
    pub width: u32,
    /// True when the region is to be rectified.
    pub do_rectify: bool,
}

/// `sensor_msgs/msg/CameraInfo`: the intrinsics, distortion, rectifying rotation and
/// projection of one camera of a (stereo) rig, row-major matrices, pixels and metres.
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
pub struct CameraInfo {
    /// Time and the camera's optical frame.
    pub header: Header,
    /// Rows of the images, pixels.
    pub height: u32,
    /// Columns of the images, pixels.
    pub width: u32,
    /// `plumb_bob`, `rational_polynomial`, `equidistant`, or empty.
    pub distortion_model: String,
    /// Distortion coefficients (`k1 k2 t1 t2 k3` for `plumb_bob`).
    pub d: Vec<f64>,
    /// Raw intrinsics, 3x3 row-major.
    #[serde(with = "fixed")]
    pub k: [f64; 9],
    /// Rectifying rotation, 3x3 row-major (rectified from raw camera frame).
    #[serde(with = "fixed")]
    pub r: [f64; 9],
    /// Projection of the rectified camera, 3x4 row-major; `P[3] = -fx' * Tx` for the
    /// right camera of a horizontal stereo pair (Tx the baseline, metres).
    #[serde(with = "fixed")]
    pub p: [f64; 12],
    /// Horizontal binning (0 or 1: none).
    pub binning_x: u32,
    /// Vertical binning (0 or 1: none).
    pub binning_y: u32,
    /// Region of interest.
    pub roi: RegionOfInterest,
}
ros_type!(CameraInfo, "sensor_msgs/msg/CameraInfo");

/// `sensor_msgs/msg/PointField`: one field of a [`PointCloud2`] point.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct PointField {
    /// Field name (`x`, `y`, `z`, ...).
    pub name: String,
    /// Byte offset in the point.
    pub offset: u32,
    /// Type code (7: FLOAT32, 8: FLOAT64).
    pub datatype: u8,
    /// Elements in the field.
    pub count: u32,
}

impl PointField {
    /// The FLOAT32 type code.
    pub const FLOAT32: u8 = 7;
}

/// `sensor_msgs/msg/PointCloud2`: points as packed records.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct PointCloud2 {
    /// Time and the frame the points are in.
    pub header: Header,
    /// Rows (1 for an unordered cloud).
    pub height: u32,
    /// Points per row.
    pub width: u32,
    /// The fields of a point.
    pub fields: Vec<PointField>,
    /// True when multi-byte values are big-endian.
    pub is_bigendian: bool,
    /// Bytes per point.
    pub point_step: u32,
    /// Bytes per row.
    pub row_step: u32,
    /// The points.
    #[serde(with = "serde_bytes")]
    pub data: Vec<u8>,
    /// True when no point is invalid.
    pub is_dense: bool,
}
ros_type!(PointCloud2, "sensor_msgs/msg/PointCloud2");
