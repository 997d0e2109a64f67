//! What opening a camera input reads of every message of its topics, in one pass over the
//! bag ([`Bag::visit_heads`]: each chunk read and decompressed once, and a chunk that is
//! not kept for the reads only as far as needed): the header stamp of every image and
//! every `camera_info` (checked to give one calibration).

use crate::bag::{Bag, Topic};
use crate::error::RosError;
use crate::msg::{CameraInfo, decode_header};

use super::calib_error;

/// Bytes of an image message read for its header (the 4-byte CDR header, the stamp and
/// the `frame_id`); a longer header is read whole.
const IMAGE_HEAD_BYTES: usize = 1024;

/// The images of one topic: their header stamps and the first one's `frame_id`.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub(crate) struct Stamps {
    /// The header stamp of each message, nanoseconds, in the topic's order.
    pub(crate) stamps_ns: Vec<i64>,
    /// The `frame_id` of the first message.
    pub(crate) frame_id: String,
}

/// The stamps of each topic of `images` and the calibration of each `camera_info` topic
/// of `infos` (its first message, checked to be the same in every other), read in one
/// visit of the bag.
///
/// # Errors
/// [`RosError::Decode`] naming the message whose header or `camera_info` does not decode;
/// [`RosError::Calibration`] for a `camera_info` topic without messages or whose
/// calibration changes.
pub(crate) fn scan(
    bag: &Bag,
    images: &[&Topic],
    infos: &[&Topic],
) -> Result<(Vec<Stamps>, Vec<CameraInfo>), RosError> {
    if let Some(t) = infos.iter().find(|t| t.entries.is_empty()) {
        return Err(calib_error(
            bag,
            format!("{} has no message: the rig is unknown", t.name),
        ));
    }
    let mut stamps: Vec<Stamps> = images
        .iter()
        .map(|t| Stamps {
            stamps_ns: vec![0; t.entries.len()],
            frame_id: String::new(),
        })
        .collect();
    let mut all_infos: Vec<Vec<Option<CameraInfo>>> =
        infos.iter().map(|t| vec![None; t.entries.len()]).collect();
    let topics: Vec<&Topic> = images.iter().chain(infos).copied().collect();
    let n = images.len();
    // Of an image, its header only; of a camera_info, all of it.
    let heads: Vec<Option<usize>> = (0..topics.len())
        .map(|k| (k < n).then_some(IMAGE_HEAD_BYTES))
        .collect();
    bag.visit_heads(&topics, &heads, |k, i, bytes| {
        if k < n {
            let decoded = match decode_header(bytes) {
                // A header longer than the bytes read: read the whole message.
                Err(_) if bytes.len() >= IMAGE_HEAD_BYTES => {
                    decode_header(&bag.read(topics[k], i)?)
                }
                other => other,
            };
            let h = decoded.map_err(|e| RosError::Decode {
                path: bag.path().to_owned(),
                topic: topics[k].name.clone(),
                index: i,
                msg_type: topics[k].msg_type.clone(),
                message: e.0,
            })?;
            stamps[k].stamps_ns[i] = h.stamp.as_nanos();
            if i == 0 {
                stamps[k].frame_id = h.frame_id;
            }
        } else {
            all_infos[k - n][i] = Some(bag.decode_bytes(topics[k], i, bytes)?);
        }
        Ok(())
    })?;
    let mut out = Vec::with_capacity(infos.len());
    for (topic, list) in infos.iter().zip(all_infos) {
        let list: Vec<CameraInfo> = list.into_iter().flatten().collect();
        let Some(first) = list.first() else {
            return Err(calib_error(
                bag,
                format!("{} has no message: the rig is unknown", topic.name),
            ));
        };
        let key = |c: &CameraInfo| (c.width, c.height, c.d.clone(), c.k, c.r, c.p);
        if let Some(i) = list.iter().position(|c| key(c) != key(first)) {
            return Err(calib_error(
                bag,
                format!(
                    "{}: message {i} gives another calibration than message 0 (a changing rig is not supported)",
                    topic.name
                ),
            ));
        }
        out.push(first.clone());
    }
    Ok((stamps, out))
}
