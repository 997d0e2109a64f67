//! What opening a camera input reads of every message of its topics, in one pass over the
//! bag ([`Bag::visit`]: each chunk read and decompressed once): the header stamp of every
//! image and every `camera_info` (checked to give one calibration).

use crate::bag::{Bag, Topic};
use crate::error::RosError;
use crate::msg::{CameraInfo, decode_header};

use super::calib_error;

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
    bag.visit(&topics, |k, i, bytes| {
        if k < n {
            let h = decode_header(bytes).map_err(|e| RosError::Decode {
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
