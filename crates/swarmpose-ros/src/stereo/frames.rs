//! What a sequence read from a bag holds, stereo or RGB-D ([`crate::BagSequence`],
//! [`crate::BagRgbdSequence`]): the bag, its two image topics paired frame by frame by
//! header stamp ([`super::pairing`]), the image size, the first camera's `camera_info`
//! and `frame_id`, and the images left without a partner.

use std::path::Path;

use super::pairing::{Paired, UnpairedImage};
use crate::bag::{Bag, Topic};
use crate::error::RosError;
use crate::msg::CameraInfo;

/// What a bag adds to a sequence for the ROS 2 outputs.
#[derive(Debug, Clone, PartialEq)]
pub struct BagInfo {
    /// The left (RGB-D: colour) images' `frame_id`.
    pub frame_id: String,
    /// The left (RGB-D: colour) camera's `camera_info`.
    pub camera_info: CameraInfo,
    /// The header stamp of each frame, nanoseconds.
    pub stamps_ns: Vec<i64>,
    /// The left and right image topics (RGB-D: the colour and depth ones).
    pub topics: (String, String),
    /// The images left without a partner (in no frame), in stamp order.
    pub unpaired: Vec<UnpairedImage>,
    /// Where reading stopped early (a cut bag), if it did.
    pub stopped: Option<String>,
}

/// A bag's two image topics paired into frames.
#[derive(Debug)]
pub struct BagFrames {
    bag: Bag,
    /// The first (left, colour) and the second (right, depth) image topic.
    topics: [Topic; 2],
    paired: Paired,
    /// Width and height of every image, pixels.
    size: (usize, usize),
    info: CameraInfo,
    frame_id: String,
}

impl BagFrames {
    /// The frames `paired` of `topics` of `bag`, images of `size` (width, height) pixels,
    /// the first camera's `camera_info` and images' `frame_id`.
    pub(crate) fn new(
        bag: Bag,
        topics: [Topic; 2],
        paired: Paired,
        size: (usize, usize),
        (info, frame_id): (CameraInfo, String),
    ) -> Self {
        Self {
            bag,
            topics,
            paired,
            size,
            info,
            frame_id,
        }
    }

    /// The bag.
    #[must_use]
    pub fn bag(&self) -> &Bag {
        &self.bag
    }

    /// The two image topics: left and right (RGB-D: colour and depth).
    #[must_use]
    pub fn topics(&self) -> (&str, &str) {
        (&self.topics[0].name, &self.topics[1].name)
    }

    /// Number of frames.
    #[must_use]
    pub fn len(&self) -> usize {
        self.paired.frames.len()
    }

    /// True when there are no frames.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.paired.frames.is_empty()
    }

    /// Width and height of the images, pixels.
    #[must_use]
    pub fn image_size(&self) -> (usize, usize) {
        self.size
    }

    /// The header stamp of each frame's first (left, colour) image, nanoseconds.
    #[must_use]
    pub fn stamps_ns(&self) -> Vec<i64> {
        self.paired.frames.iter().map(|f| f.2).collect()
    }

    /// The first (left, colour) camera's `camera_info` (its first message).
    #[must_use]
    pub fn camera_info(&self) -> &CameraInfo {
        &self.info
    }

    /// The first (left, colour) images' `frame_id` (the camera's optical frame).
    #[must_use]
    pub fn frame_id(&self) -> &str {
        &self.frame_id
    }

    /// The images left without a partner, in stamp order.
    #[must_use]
    pub fn unpaired(&self) -> &[UnpairedImage] {
        &self.paired.unpaired
    }

    /// What the pairing said (images without a partner), and where reading stopped (a
    /// cut bag).
    #[must_use]
    pub fn notes(&self) -> &[String] {
        &self.paired.notes
    }

    /// Seconds from the first frame's stamp to frame `i`'s, or `None` out of range.
    #[must_use]
    pub fn timestamp_s(&self, i: usize) -> Option<f64> {
        let first = self.paired.frames.first()?.2;
        Some(crate::convert::seconds_since(
            first,
            self.paired.frames.get(i)?.2,
        ))
    }

    /// What the bag adds to the sequence for the ROS 2 outputs.
    #[must_use]
    pub fn info(&self) -> BagInfo {
        let (a, b) = self.topics();
        BagInfo {
            frame_id: self.frame_id.clone(),
            camera_info: self.info.clone(),
            stamps_ns: self.stamps_ns(),
            topics: (a.to_owned(), b.to_owned()),
            unpaired: self.unpaired().to_vec(),
            stopped: self.bag.stopped().map(str::to_owned),
        }
    }

    /// The bag's path.
    pub(crate) fn path(&self) -> &Path {
        self.bag.path()
    }

    /// The two topics with the message of each in frame `i`.
    ///
    /// # Errors
    /// [`RosError::Container`] for a frame out of range.
    pub(crate) fn messages(&self, i: usize) -> Result<[(&Topic, usize); 2], RosError> {
        let &(a, b, _) = self
            .paired
            .frames
            .get(i)
            .ok_or_else(|| RosError::Container {
                path: self.bag.path().to_owned(),
                message: format!("frame {i} out of range ({} frames)", self.len()),
            })?;
        Ok([(&self.topics[0], a), (&self.topics[1], b)])
    }

    /// Checks that message `index` of `topic`, `w` x `h` pixels, is of the stream's size.
    ///
    /// # Errors
    /// [`RosError::Image`] naming the topic and message when it is not.
    pub(crate) fn check_size(
        &self,
        (topic, index): (&Topic, usize),
        (w, h): (usize, usize),
    ) -> Result<(), RosError> {
        if (w, h) == self.size {
            return Ok(());
        }
        Err(RosError::Image {
            path: self.bag.path().to_owned(),
            topic: topic.name.clone(),
            index,
            message: format!(
                "a {w}x{h} image in a {}x{} stream",
                self.size.0, self.size.1
            ),
        })
    }
}

/// The methods of [`swarmpose_datasets::StereoSequence`] and
/// [`swarmpose_datasets::DepthSequence`] a bag's sequence answers from its
/// [`BagFrames`] (the field `frames`).
macro_rules! bag_sequence_methods {
    () => {
        fn root(&self) -> &std::path::Path {
            self.frames.path()
        }

        fn len(&self) -> usize {
            self.frames.len()
        }

        fn notes(&self) -> &[String] {
            self.frames.notes()
        }

        fn ground_truth(&self) -> Option<&[nalgebra::Isometry3<f64>]> {
            None
        }

        fn timestamp_s(&self, i: usize) -> Option<f64> {
            self.frames.timestamp_s(i)
        }
    };
}
pub(crate) use bag_sequence_methods;
