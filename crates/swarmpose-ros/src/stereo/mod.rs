//! Stereo frames from a ROS 2 bag, behind [`swarmpose_datasets::StereoSequence`]: the
//! camera topics found or named ([`topics`]), left and right paired by header stamp
//! ([`pairing`]), the rig from `camera_info` ([`calib`]), images to gray
//! ([`crate::image`]). Opening reads every image once for its header stamp and every
//! `camera_info`, in one pass (`scan.rs`); a frame is then read, converted and (raw
//! streams) rectified when asked for.

pub mod calib;
pub mod frames;
pub mod pairing;
pub(crate) mod scan;
pub mod topics;

use std::path::Path;

use swarmpose_datasets::{DatasetError, RectifiedStereo, StereoPair, StereoSequence};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::rectify::remap;

use crate::bag::{Bag, Topic};
use crate::error::RosError;
use crate::image::{compressed_to_gray, image_into_gray};
use crate::msg::{CompressedImage, Image, RosMessage};
use calib::{Rig, rig_from_camera_info};
use frames::{BagFrames, bag_sequence_methods};
use pairing::pair_frames;
use scan::scan;
use topics::{CameraTopics, cameras, info_topic_of, is_image_type};

/// How to find the stereo input of a bag.
#[derive(Debug, Clone, Default, PartialEq, Eq)]
pub struct StereoOptions {
    /// The left image topic (found when `None`).
    pub left: Option<String>,
    /// The right image topic (found when `None`).
    pub right: Option<String>,
    /// The depth image topic of an RGB-D bag (found when `None`: a bag with one colour
    /// and one depth camera); with it, `left` names the colour topic.
    pub depth: Option<String>,
    /// Largest difference of the header stamps of a left and a right image paired into
    /// a frame, nanoseconds (0: equal stamps).
    pub stamp_tolerance_ns: i64,
}

impl StereoOptions {
    /// The options with the stamp tolerance in milliseconds (the unit of the command
    /// line and of Python).
    ///
    /// # Errors
    /// A one-line message for a tolerance that is negative or not a number.
    pub fn with_tolerance_ms(
        left: Option<String>,
        right: Option<String>,
        tolerance_ms: f64,
    ) -> Result<Self, String> {
        if !(tolerance_ms.is_finite() && tolerance_ms >= 0.0) {
            return Err(format!(
                "the stamp tolerance must be a number of milliseconds, 0 or more (not {tolerance_ms})"
            ));
        }
        Ok(Self {
            left,
            right,
            depth: None,
            stamp_tolerance_ns: (tolerance_ms * 1e6).round() as i64,
        })
    }
}

/// A stereo sequence read from a ROS 2 bag.
#[derive(Debug)]
pub struct BagSequence {
    /// The left and right topics paired into frames.
    frames: BagFrames,
    rig: Rig,
}

pub(crate) fn topics_error(bag: &Bag, message: String) -> RosError {
    RosError::Topics {
        path: bag.path().to_owned(),
        message: format!("{message}; {}", bag.listing()),
    }
}

pub(crate) fn calib_error(bag: &Bag, message: String) -> RosError {
    RosError::Calibration {
        path: bag.path().to_owned(),
        message,
    }
}

/// The camera of image topic `name`, which must exist and have a `camera_info` beside it.
///
/// # Errors
/// [`RosError::Topics`] for no such image topic; [`RosError::Calibration`] without a
/// `camera_info`.
pub(crate) fn named_camera(bag: &Bag, name: &str) -> Result<CameraTopics, RosError> {
    let t = bag
        .topic(name)
        .ok_or_else(|| topics_error(bag, format!("no topic {name}")))?;
    if !is_image_type(&t.msg_type) {
        return Err(topics_error(
            bag,
            format!("{name} is a {}, not an image topic", t.msg_type),
        ));
    }
    let info = info_topic_of(bag, name).ok_or_else(|| {
        calib_error(
            bag,
            format!("no camera_info topic beside {name}: the rig is unknown"),
        )
    })?;
    Ok(CameraTopics {
        image: name.to_owned(),
        info,
    })
}

/// The camera topics named in `opts`, or found.
fn choose(bag: &Bag, opts: &StereoOptions) -> Result<(CameraTopics, CameraTopics), RosError> {
    let named = |name: &str| named_camera(bag, name);
    if let (Some(l), Some(r)) = (&opts.left, &opts.right) {
        return Ok((named(l)?, named(r)?));
    }
    if opts.left.is_some() != opts.right.is_some() {
        return Err(topics_error(
            bag,
            "name both the left and the right topic, or neither".to_owned(),
        ));
    }
    let images: Vec<&str> = bag
        .topics()
        .iter()
        .filter(|t| is_image_type(&t.msg_type) && !t.entries.is_empty())
        .map(|t| t.name.as_str())
        .collect();
    let cams = cameras(bag);
    match (images.len(), cams.len()) {
        (0, _) => Err(topics_error(
            bag,
            "no image topic (sensor_msgs/msg/Image or CompressedImage with messages)".to_owned(),
        )),
        (_, 0) => Err(calib_error(
            bag,
            format!(
                "no camera_info beside the image topics {}: the rig is unknown",
                images.join(", ")
            ),
        )),
        (_, 1) => Err(topics_error(
            bag,
            format!(
                "one camera only ({}): stereo needs two image topics with camera_info",
                cams[0].image
            ),
        )),
        (_, 2) => order(bag, cams[0].clone(), cams[1].clone()),
        (_, n) => Err(topics_error(
            bag,
            format!("{n} cameras with camera_info: name the pair with --left and --right"),
        )),
    }
}

/// The two cameras as (left, right): the right one is to the right in its `P`, or named
/// `right`.
fn order(
    bag: &Bag,
    a: CameraTopics,
    b: CameraTopics,
) -> Result<(CameraTopics, CameraTopics), RosError> {
    let tx = |c: &CameraTopics| {
        bag.topic(&c.info)
            .and_then(|t| topics::first_info(bag, t))
            .map_or(0.0, |i| i.p[3])
    };
    let (ta, tb) = (tx(&a), tx(&b));
    if ta == 0.0 && tb < 0.0 {
        return Ok((a, b));
    }
    if tb == 0.0 && ta < 0.0 {
        return Ok((b, a));
    }
    let has = |c: &CameraTopics, w: &str| c.image.to_lowercase().contains(w);
    if has(&a, "left") && has(&b, "right") {
        return Ok((a, b));
    }
    if has(&b, "left") && has(&a, "right") {
        return Ok((b, a));
    }
    Err(topics_error(
        bag,
        format!(
            "cannot tell left from right among {} and {} (neither P nor the names say): name them \
             with --left and --right",
            a.image, b.image
        ),
    ))
}

/// Image message `index` of `topic` as gray.
pub(crate) fn gray(bag: &Bag, topic: &Topic, index: usize) -> Result<GrayImage, RosError> {
    let image_error = |message: String| RosError::Image {
        path: bag.path().to_owned(),
        topic: topic.name.clone(),
        index,
        message,
    };
    if topic.msg_type == CompressedImage::TYPE {
        let m: CompressedImage = bag.decode(topic, index)?;
        compressed_to_gray(&m).map_err(image_error)
    } else {
        let m: Image = bag.decode(topic, index)?;
        image_into_gray(m).map_err(image_error)
    }
}

impl BagSequence {
    /// Opens the bag at `path` and finds its stereo input.
    ///
    /// # Errors
    /// As [`Bag::open`]; [`RosError::Topics`] (listing the topics) when there is no
    /// image topic, one camera only, an ambiguous choice, or no left/right pair within
    /// the tolerance; [`RosError::Calibration`] for a missing or unusable
    /// `camera_info`; [`RosError::Image`] for an encoding that is not read.
    pub fn open(path: &Path, opts: &StereoOptions) -> Result<Self, RosError> {
        Self::from_bag(Bag::open(path)?, opts)
    }

    /// Finds the stereo input of an opened bag.
    ///
    /// # Errors
    /// As [`BagSequence::open`].
    pub fn from_bag(bag: Bag, opts: &StereoOptions) -> Result<Self, RosError> {
        let (lc, rc) = choose(&bag, opts)?;
        let topic = |n: &str| {
            bag.topic(n)
                .cloned()
                .ok_or_else(|| topics_error(&bag, format!("no topic {n}")))
        };
        let (left, right) = (topic(&lc.image)?, topic(&rc.image)?);
        let (left_info, right_info) = (topic(&lc.info)?, topic(&rc.info)?);
        let (stamps, infos) = scan(&bag, &[&left, &right], &[&left_info, &right_info])?;
        let (Ok([left_stamps, right_stamps]), Ok([li, ri])) =
            (<[_; 2]>::try_from(stamps), <[_; 2]>::try_from(infos))
        else {
            return Err(topics_error(
                &bag,
                "the camera topics were not read".to_owned(),
            ));
        };
        let (ls, rs, frame_id) = (
            left_stamps.stamps_ns,
            right_stamps.stamps_ns,
            left_stamps.frame_id,
        );
        let paired = pair_frames(
            &bag,
            [(&left, &ls[..]), (&right, &rs[..])],
            ["left", "right"],
            opts.stamp_tolerance_ns,
        )?;
        let (first_l, first_r, _) = paired.frames[0];
        let (l0, r0) = (gray(&bag, &left, first_l)?, gray(&bag, &right, first_r)?);
        let rig = rig_from_camera_info(&li, &ri, (l0.width, l0.height), (r0.width, r0.height))
            .map_err(|m| calib_error(&bag, format!("{} and {}: {m}", lc.info, rc.info)))?;
        let size = (l0.width, l0.height);
        Ok(Self {
            frames: BagFrames::new(bag, [left, right], paired, size, (li, frame_id)),
            rig,
        })
    }

    /// The bag, its left and right topics and their frames.
    #[must_use]
    pub fn frames(&self) -> &BagFrames {
        &self.frames
    }

    /// The rig: rectified images as they are, or raw ones with their remap tables.
    #[must_use]
    pub fn rig(&self) -> &Rig {
        &self.rig
    }

    /// Frame `i`, rectified.
    ///
    /// # Errors
    /// [`RosError`] naming the topic and message.
    pub fn read_frame(&self, i: usize) -> Result<StereoPair, RosError> {
        let [l, r] = self.frames.messages(i)?;
        let bag = self.frames.bag();
        let (left, right) = (gray(bag, l.0, l.1)?, gray(bag, r.0, r.1)?);
        self.frames.check_size(l, (left.width, left.height))?;
        self.frames.check_size(r, (right.width, right.height))?;
        Ok(match &self.rig {
            Rig::Rectified(_) => StereoPair { left, right },
            Rig::Raw {
                left: lt,
                right: rt,
                ..
            } => StereoPair {
                left: remap(left.view(), lt),
                right: remap(right.view(), rt),
            },
        })
    }
}

/// A [`RosError`] as the sequence loaders' error: the bag and the message.
pub(crate) fn to_dataset(e: &RosError) -> DatasetError {
    let path = e.path().to_owned();
    let full = e.to_string();
    let prefix = format!("{}: ", path.display());
    DatasetError::Parse {
        message: full.strip_prefix(&prefix).unwrap_or(&full).to_owned(),
        path,
        line: 0,
    }
}

impl StereoSequence for BagSequence {
    bag_sequence_methods!();

    fn layout(&self) -> &'static str {
        "ros2 bag"
    }

    fn calibration(&self) -> RectifiedStereo {
        self.rig.rectified()
    }

    fn image_size(&self) -> (usize, usize) {
        self.frames.image_size()
    }

    fn frame(&self, i: usize) -> Result<StereoPair, DatasetError> {
        self.read_frame(i).map_err(|e| to_dataset(&e))
    }
}
