//! Which topics of a bag are the left and right cameras, and their `camera_info`.
//!
//! Named topics are taken as given. Otherwise the candidates are the `Image` and
//! `CompressedImage` topics that have a `CameraInfo` topic in their namespace
//! (`/ns/image_raw` and `/ns/image_raw/compressed` go with `/ns/camera_info`); with
//! exactly two cameras, the right one is the camera whose projection `P` puts it to the
//! right (`P[0][3] < 0`), and otherwise the one named `right`. Anything else is refused
//! with the list of topics.

use crate::bag::{Bag, Topic};
use crate::msg::{CameraInfo, CompressedImage, Image, RosMessage};

/// The topics of one camera: images and their `camera_info`.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CameraTopics {
    /// The image topic.
    pub image: String,
    /// The `CameraInfo` topic.
    pub info: String,
}

/// True for the image types read.
#[must_use]
pub fn is_image_type(msg_type: &str) -> bool {
    msg_type == Image::TYPE || msg_type == CompressedImage::TYPE
}

/// The namespace of an image topic: the topic without its last name, and without a
/// trailing `/compressed` first.
fn namespace(topic: &str) -> &str {
    let t = topic.strip_suffix("/compressed").unwrap_or(topic);
    t.rsplit_once('/').map_or("", |(ns, _)| ns)
}

/// The `CameraInfo` topic of image topic `image`: the one in the nearest enclosing
/// namespace.
#[must_use]
pub fn info_topic_of(bag: &Bag, image: &str) -> Option<String> {
    let mut ns = namespace(image);
    loop {
        let want = format!("{ns}/camera_info");
        if let Some(t) = bag
            .topics()
            .iter()
            .find(|t| t.name == want && t.msg_type == CameraInfo::TYPE)
        {
            return Some(t.name.clone());
        }
        ns = ns.rsplit_once('/').map(|x| x.0)?;
    }
}

/// The image topics with their `camera_info` (those without one are left out).
#[must_use]
pub fn cameras(bag: &Bag) -> Vec<CameraTopics> {
    bag.topics()
        .iter()
        .filter(|t| is_image_type(&t.msg_type) && !t.entries.is_empty())
        .filter_map(|t| {
            Some(CameraTopics {
                image: t.name.clone(),
                info: info_topic_of(bag, &t.name)?,
            })
        })
        .collect()
}

/// The first `CameraInfo` of `topic`, if it decodes.
pub(crate) fn first_info(bag: &Bag, topic: &Topic) -> Option<CameraInfo> {
    bag.decode::<CameraInfo>(topic, 0).ok()
}
