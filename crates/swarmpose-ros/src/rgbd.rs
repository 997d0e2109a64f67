//! RGB-D frames from a ROS 2 bag, behind [`swarmpose_datasets::DepthSequence`]: a colour
//! image topic and a depth image topic (`sensor_msgs/Image`, `16UC1` in millimetres or
//! `32FC1` in metres, registered to the colour camera: the same size), each with a
//! `camera_info`.
//!
//! The topics are named (`depth`, and `left` for the colour one) or found: a bag whose
//! cameras (image topics with `camera_info`) are one colour camera and one depth camera
//! (its first image in a depth encoding) is an RGB-D bag; a bag with a depth camera and
//! more or fewer than one other camera is refused with the list of topics (name them).
//! Colour and depth are paired by header stamp as stereo images are
//! ([`crate::stereo::pairing`]). The intrinsics are the colour `camera_info`'s `K`
//! when its distortion `D` is zero, else its `P` when the colour topic is a rectified
//! one (its name has `rect`); distorted colour images are refused (the depth would need
//! the same undistortion).

use std::path::Path;

use swarmpose_datasets::{DatasetError, DepthSequence, Intrinsics, RgbdFrame};
use swarmpose_vision::image::GrayImage;

use crate::bag::{Bag, Topic};
use crate::error::RosError;
use crate::image::{DEPTH_ENCODINGS, image_to_depth_m};
use crate::msg::{CameraInfo, Image, RosMessage};
use crate::stereo::frames::{BagFrames, bag_sequence_methods};
use crate::stereo::pairing::pair_frames;
use crate::stereo::scan::scan;
use crate::stereo::topics::{CameraTopics, cameras};
use crate::stereo::{StereoOptions, calib_error, gray, named_camera, to_dataset, topics_error};

/// An RGB-D sequence read from a ROS 2 bag.
#[derive(Debug)]
pub struct BagRgbdSequence {
    /// The colour and depth topics paired into frames.
    frames: BagFrames,
    intrinsics: Intrinsics,
}

/// The encoding of the first image of `topic`, when it is a `sensor_msgs/Image` that
/// decodes.
fn first_encoding(bag: &Bag, topic: &str) -> Option<String> {
    let t = bag.topic(topic)?;
    (t.msg_type == Image::TYPE && !t.entries.is_empty())
        .then(|| bag.decode::<Image>(t, 0).ok().map(|m| m.encoding))
        .flatten()
}

fn is_depth_camera(bag: &Bag, c: &CameraTopics) -> bool {
    first_encoding(bag, &c.image).is_some_and(|e| DEPTH_ENCODINGS.contains(&e.as_str()))
}

fn names(cams: &[CameraTopics]) -> String {
    if cams.is_empty() {
        return "none".to_owned();
    }
    cams.iter()
        .map(|c| c.image.as_str())
        .collect::<Vec<_>>()
        .join(", ")
}

/// The `(colour, depth)` cameras of `bag` when it is an RGB-D bag (a depth topic named in
/// `opts`, or found); `None` when it is not one (no depth camera, or a stereo pair
/// named).
///
/// # Errors
/// [`RosError::Topics`] (listing the topics) when the choice is ambiguous or the
/// options do not fit or a named image topic does not exist; [`RosError::Calibration`]
/// when a named topic has no `camera_info` beside it.
pub fn rgbd_cameras(
    bag: &Bag,
    opts: &StereoOptions,
) -> Result<Option<(CameraTopics, CameraTopics)>, RosError> {
    if opts.depth.is_none() && opts.right.is_some() {
        return Ok(None);
    }
    if opts.depth.is_some() && opts.right.is_some() {
        return Err(topics_error(
            bag,
            "a depth topic and a right topic are named: name --left and --right for stereo, \
             or --depth (and --left for the colour topic) for RGB-D"
                .to_owned(),
        ));
    }
    let all = cameras(bag);
    let depth = match &opts.depth {
        Some(d) => named_camera(bag, d)?,
        None => {
            let found: Vec<CameraTopics> = all
                .iter()
                .filter(|c| is_depth_camera(bag, c))
                .cloned()
                .collect();
            match found.len() {
                0 => return Ok(None),
                1 => found[0].clone(),
                n => {
                    return Err(topics_error(
                        bag,
                        format!(
                            "{n} depth cameras ({}): name the depth topic with --depth",
                            names(&found)
                        ),
                    ));
                }
            }
        }
    };
    let colour = match &opts.left {
        Some(c) => named_camera(bag, c)?,
        None => {
            let others: Vec<CameraTopics> = all
                .into_iter()
                .filter(|c| c.image != depth.image && !is_depth_camera(bag, c))
                .collect();
            if others.len() != 1 {
                return Err(topics_error(
                    bag,
                    format!(
                        "depth camera {} with {} colour cameras ({}): an RGB-D input is one colour \
                         and one depth camera; name them with --left (colour) and --depth",
                        depth.image,
                        others.len(),
                        names(&others)
                    ),
                ));
            }
            others[0].clone()
        }
    };
    Ok(Some((colour, depth)))
}

/// Depth image `index` of `topic`, metres, with its width and height.
fn depth_m(bag: &Bag, topic: &Topic, index: usize) -> Result<(Vec<f32>, usize, usize), RosError> {
    let image_error = |message: String| RosError::Image {
        path: bag.path().to_owned(),
        topic: topic.name.clone(),
        index,
        message,
    };
    if topic.msg_type != Image::TYPE {
        return Err(image_error(format!(
            "a depth topic of {}: depth is read from sensor_msgs/msg/Image ({})",
            topic.msg_type,
            DEPTH_ENCODINGS.join(", ")
        )));
    }
    let m: Image = bag.decode(topic, index)?;
    if !DEPTH_ENCODINGS.contains(&m.encoding.as_str()) {
        return Err(image_error(format!(
            "depth encoding '{}' is not 16UC1 (millimetres) or 32FC1 (metres)",
            m.encoding
        )));
    }
    let d = image_to_depth_m(&m).map_err(image_error)?;
    Ok((d, m.width as usize, m.height as usize))
}

/// The pinhole intrinsics of the colour camera (see the module documentation).
fn intrinsics(topic: &str, info: &CameraInfo) -> Result<Intrinsics, String> {
    let (k, p) = (info.k, info.p);
    if info.d.iter().all(|&x| x == 0.0) {
        return Ok(Intrinsics {
            fx: k[0],
            fy: k[4],
            cx: k[2],
            cy: k[5],
        });
    }
    if topic.contains("rect") {
        return Ok(Intrinsics {
            fx: p[0],
            fy: p[5],
            cx: p[2],
            cy: p[6],
        });
    }
    Err(format!(
        "{topic} has distortion D = {:?} and is not a rectified topic (no 'rect' in its name): \
         RGB-D images are read undistorted; record the rectified colour topic",
        info.d
    ))
}

impl BagRgbdSequence {
    /// Opens the bag at `path` and finds its RGB-D input.
    ///
    /// # Errors
    /// As [`Bag::open`] and [`BagRgbdSequence::from_bag`]; [`RosError::Topics`] when the
    /// bag has no depth camera.
    pub fn open(path: &Path, opts: &StereoOptions) -> Result<Self, RosError> {
        let bag = Bag::open(path)?;
        match rgbd_cameras(&bag, opts)? {
            Some((c, d)) => Self::from_bag(bag, &c, &d, opts),
            None => Err(topics_error(
                &bag,
                "no depth camera (an Image topic in 16UC1 or 32FC1 with camera_info)".to_owned(),
            )),
        }
    }

    /// The RGB-D input of an opened bag from its `colour` and `depth` cameras.
    ///
    /// # Errors
    /// [`RosError::Topics`] when no colour image has a depth image within the stamp
    /// tolerance; [`RosError::Image`] for a depth topic that is not `16UC1` or `32FC1`
    /// or whose images are not of the colour images' size; [`RosError::Calibration`]
    /// for a colour `camera_info` that disagrees with the images, changes, is distorted
    /// or is not a plausible camera.
    pub fn from_bag(
        bag: Bag,
        colour: &CameraTopics,
        depth: &CameraTopics,
        opts: &StereoOptions,
    ) -> Result<Self, RosError> {
        let topic = |n: &str| {
            bag.topic(n)
                .cloned()
                .ok_or_else(|| topics_error(&bag, format!("no topic {n}")))
        };
        let (ct, dt, info_t) = (
            topic(&colour.image)?,
            topic(&depth.image)?,
            topic(&colour.info)?,
        );
        let (stamps, infos) = scan(&bag, &[&ct, &dt], &[&info_t])?;
        let (Ok([cs, ds]), Ok([info])) = (<[_; 2]>::try_from(stamps), <[_; 1]>::try_from(infos))
        else {
            return Err(topics_error(
                &bag,
                "the camera topics were not read".to_owned(),
            ));
        };
        let paired = pair_frames(
            &bag,
            [(&ct, &cs.stamps_ns[..]), (&dt, &ds.stamps_ns[..])],
            ["colour", "depth"],
            opts.stamp_tolerance_ns,
        )?;
        let (c0, d0, _) = paired.frames[0];
        let g = gray(&bag, &ct, c0)?;
        let size = (g.width, g.height);
        let (_, dw, dh) = depth_m(&bag, &dt, d0)?;
        if (dw, dh) != size {
            return Err(RosError::Image {
                path: bag.path().to_owned(),
                topic: dt.name.clone(),
                index: d0,
                message: format!(
                    "depth images of {dw}x{dh} but colour images of {}x{} ({}): the depth must be \
                     registered to the colour camera (an aligned depth topic)",
                    size.0, size.1, ct.name
                ),
            });
        }
        let calib = |m: String| calib_error(&bag, format!("{}: {m}", colour.info));
        if (info.width as usize, info.height as usize) != size {
            return Err(calib(format!(
                "camera_info is for {}x{} images, the images are {}x{}",
                info.width, info.height, size.0, size.1
            )));
        }
        let k = intrinsics(&ct.name, &info).map_err(calib)?;
        if let Some(why) = k.implausibility(size.0, size.1) {
            return Err(calib(why));
        }
        Ok(Self {
            frames: BagFrames::new(bag, [ct, dt], paired, size, (info, cs.frame_id)),
            intrinsics: k,
        })
    }

    /// The bag, its colour and depth topics and their frames.
    #[must_use]
    pub fn frames(&self) -> &BagFrames {
        &self.frames
    }

    /// Frame `i`: the colour image as gray and the depth, metres.
    ///
    /// # Errors
    /// [`RosError`] naming the topic and message.
    pub fn read_frame(&self, i: usize) -> Result<(GrayImage, Vec<f32>), RosError> {
        let [c, d] = self.frames.messages(i)?;
        let bag = self.frames.bag();
        let g = gray(bag, c.0, c.1)?;
        let (depth, dw, dh) = depth_m(bag, d.0, d.1)?;
        self.frames.check_size(c, (g.width, g.height))?;
        self.frames.check_size(d, (dw, dh))?;
        Ok((g, depth))
    }
}

impl DepthSequence for BagRgbdSequence {
    bag_sequence_methods!();

    fn layout(&self) -> &'static str {
        "ros2 bag, rgb-d"
    }

    fn camera(&self) -> Result<(Intrinsics, (usize, usize)), DatasetError> {
        Ok((self.intrinsics, self.frames.image_size()))
    }

    fn frame(&self, i: usize) -> Result<RgbdFrame, DatasetError> {
        let (gray, depth_m) = self.read_frame(i).map_err(|e| to_dataset(&e))?;
        Ok(RgbdFrame { gray, depth_m })
    }
}
