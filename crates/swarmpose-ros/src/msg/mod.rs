//! The ROS 2 message types swarmpose reads and writes, as serde structs whose field order
//! is the `.msg` order, so that one set of types serves bag input, `odometry.mcap` output
//! and a live node. Bytes are CDR (little- or big-endian, with the 4-byte encapsulation
//! header of ROS 2 messages) through the `cdr-encoding` crate ([`decode`], [`encode`]).
//!
//! Each type names itself ([`RosMessage::TYPE`]); its `.msg` definition is in one table
//! (`definitions.rs`), and [`schema_text`] joins it with those of the types it uses, in the `ros2msg` schema
//! encoding that MCAP readers (Foxglove, the Rerun viewer, `ros2 bag`) expect.

mod definitions;
mod geometry;
mod sensor;

use byteorder::{BigEndian, LittleEndian};
use serde::de::{self, DeserializeOwned, SeqAccess, Visitor};
use serde::ser::SerializeTuple;
use serde::{Deserialize, Deserializer, Serialize, Serializer};

use crate::error::CdrError;

pub use definitions::{definition_of, schema_text};
pub use geometry::{
    DiagnosticArray, DiagnosticStatus, KeyValue, Log, Odometry, Path, Point, Pose, PoseStamped,
    PoseWithCovariance, PoseWithCovarianceStamped, Quaternion, StringMsg, TfMessage, Transform,
    TransformStamped, Twist, TwistWithCovariance, Vector3,
};
pub use sensor::{CameraInfo, CompressedImage, Image, PointCloud2, PointField, RegionOfInterest};

/// A ROS 2 message type: its name and `.msg` text.
pub trait RosMessage: Serialize + DeserializeOwned {
    /// The full type name, `pkg/msg/Name`.
    const TYPE: &'static str;
}

/// `builtin_interfaces/msg/Time`: seconds and nanoseconds since the epoch (or since the
/// start of a recording without wall time).
#[derive(
    Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default, Serialize, Deserialize,
)]
pub struct Time {
    /// Whole seconds.
    pub sec: i32,
    /// Nanoseconds, `0..1_000_000_000`.
    pub nanosec: u32,
}

impl Time {
    /// Nanoseconds since the epoch.
    #[must_use]
    pub fn as_nanos(self) -> i64 {
        i64::from(self.sec) * 1_000_000_000 + i64::from(self.nanosec)
    }

    /// The time of `nanos` nanoseconds since the epoch (clamped to the `i32` seconds of
    /// the message: years 1901 to 2038).
    #[must_use]
    pub fn from_nanos(nanos: i64) -> Self {
        let sec = nanos.div_euclid(1_000_000_000);
        let nanosec = nanos.rem_euclid(1_000_000_000);
        Self {
            sec: sec.clamp(i64::from(i32::MIN), i64::from(i32::MAX)) as i32,
            nanosec: nanosec as u32,
        }
    }
}

/// `std_msgs/msg/Header`: the time of the data and the frame it is expressed in.
#[derive(Debug, Clone, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Header {
    /// Time of the data.
    pub stamp: Time,
    /// Coordinate frame of the data.
    pub frame_id: String,
}

/// CDR of a fixed-size `float64[N]` array (serde's built-in arrays stop at 32 elements;
/// covariances have 36).
pub mod fixed {
    use super::{Deserializer, SeqAccess, SerializeTuple, Serializer, Visitor, de};

    /// Serialises `N` floats without a length (a CDR array).
    ///
    /// # Errors
    /// The serialiser's.
    pub fn serialize<S: Serializer, const N: usize>(v: &[f64; N], s: S) -> Result<S::Ok, S::Error> {
        let mut t = s.serialize_tuple(N)?;
        for x in v {
            t.serialize_element(x)?;
        }
        t.end()
    }

    struct ArrayVisitor<const N: usize>;

    impl<'de, const N: usize> Visitor<'de> for ArrayVisitor<N> {
        type Value = [f64; N];

        fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
            write!(f, "{N} float64")
        }

        fn visit_seq<A: SeqAccess<'de>>(self, mut seq: A) -> Result<Self::Value, A::Error> {
            let mut out = [0.0; N];
            for (i, o) in out.iter_mut().enumerate() {
                *o = seq
                    .next_element()?
                    .ok_or_else(|| de::Error::invalid_length(i, &self))?;
            }
            Ok(out)
        }
    }

    /// Reads `N` floats without a length (a CDR array).
    ///
    /// # Errors
    /// The deserialiser's (too few bytes).
    pub fn deserialize<'de, D: Deserializer<'de>, const N: usize>(
        d: D,
    ) -> Result<[f64; N], D::Error> {
        d.deserialize_tuple(N, ArrayVisitor::<N>)
    }
}

impl RosMessage for Header {
    const TYPE: &'static str = "std_msgs/msg/Header";
}

/// The [`Header`] at the start of a serialised message whose first field is one
/// (`Image`, `CompressedImage`, `CameraInfo`, ...), without decoding the rest.
///
/// # Errors
/// As [`decode`], but bytes after the header are expected.
pub fn decode_header(bytes: &[u8]) -> Result<Header, CdrError> {
    decode_with::<Header>(bytes, true)
}

/// Most bytes a message may leave unread after its last field: CDR pads a message to a
/// multiple of 4 (more is another type's message, or a corrupt one).
const MAX_TRAILING: usize = 3;

/// Decodes a serialised ROS 2 message: the 4-byte encapsulation header (`00 01` CDR
/// little-endian, `00 00` big-endian), then the CDR of `T`.
///
/// # Errors
/// [`CdrError`] for a missing or unknown header, too few bytes for the fields, a string
/// that is not UTF-8, or bytes left over (another type's message).
pub fn decode<T: RosMessage>(bytes: &[u8]) -> Result<T, CdrError> {
    decode_with::<T>(bytes, false)
}

/// [`decode`], allowing bytes after the message when `prefix`.
fn decode_with<T: RosMessage>(bytes: &[u8], prefix: bool) -> Result<T, CdrError> {
    let Some((head, body)) = bytes.split_first_chunk::<4>() else {
        return Err(CdrError(format!(
            "{} bytes: too short for the 4-byte CDR header",
            bytes.len()
        )));
    };
    let decoded = match head[..2] {
        [0, 1] => cdr_encoding::from_bytes::<T, LittleEndian>(body),
        [0, 0] => cdr_encoding::from_bytes::<T, BigEndian>(body),
        _ => {
            return Err(CdrError(format!(
                "encapsulation {:02x} {:02x} is not plain CDR (00 00 or 00 01)",
                head[0], head[1]
            )));
        }
    };
    let (value, used) = decoded.map_err(|e| CdrError(format!("not a {}: {e}", T::TYPE)))?;
    let left = body.len().saturating_sub(used);
    if left > MAX_TRAILING && !prefix {
        return Err(CdrError(format!(
            "not a {}: {left} bytes left over after its last field",
            T::TYPE
        )));
    }
    Ok(value)
}

/// Serialises a ROS 2 message: the CDR little-endian encapsulation header, then the CDR
/// of `value`.
///
/// # Errors
/// [`CdrError`] when the serialiser fails (a sequence longer than 2³² elements).
pub fn encode<T: RosMessage>(value: &T) -> Result<Vec<u8>, CdrError> {
    let mut out = vec![0, 1, 0, 0];
    cdr_encoding::to_writer::<T, LittleEndian, _>(&mut out, value)
        .map_err(|e| CdrError(format!("cannot serialise a {}: {e}", T::TYPE)))?;
    Ok(out)
}

#[cfg(test)]
mod tests;
