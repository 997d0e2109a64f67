//! RGB-D input written at test time from the synthetic street rendered with exact depth
//! ([`swarmpose_runs::synthetic::SyntheticSequence`]): a TUM RGB-D folder of its frames
//! ([`tum_folder`]) and the ROS 2 bag of the same frames ([`rgbd_topics`]: a colour and
//! a depth `sensor_msgs/Image` topic, each with `camera_info`), which a reader must run
//! as it runs the folder; and small bags with one thing wrong ([`small_bag`]).

use std::path::{Path, PathBuf};

use swarmpose_ros::convert::seconds_since;
use swarmpose_ros::msg::{CameraInfo, Header, Image, RosMessage, Time, encode};
use swarmpose_runs::rgbd::RgbdSequence;
use swarmpose_runs::synthetic::SyntheticSequence;

use crate::bags::{TopicData, write_mcap};

/// Frames of the clip.
pub const FRAMES: usize = 6;
/// The header stamp of the first frame, nanoseconds.
pub const T0_NS: i64 = 1_305_031_102_000_000_000;
/// The time between frames, nanoseconds (30 Hz).
pub const PERIOD_NS: i64 = 33_333_333;

/// The colour image topic.
pub const COLOUR: &str = "/camera/color/image_raw";
/// The colour `camera_info` topic.
pub const COLOUR_INFO: &str = "/camera/color/camera_info";
/// The depth image topic (registered to the colour camera).
pub const DEPTH: &str = "/camera/aligned_depth/image_raw";
/// The depth `camera_info` topic.
pub const DEPTH_INFO: &str = "/camera/aligned_depth/camera_info";

/// The header stamp of frame `k`, nanoseconds.
#[must_use]
pub fn stamp(k: usize) -> i64 {
    T0_NS + k as i64 * PERIOD_NS
}

/// Writes in `dir/tum` a TUM RGB-D folder of the synthetic street whose depths are whole
/// millimetres (5 TUM units each) and whose times are those a bag of stamps [`stamp`]
/// gives (seconds since the first frame), without ground truth; returns it opened.
///
/// # Panics
/// When the folder cannot be written or read (meant for tests only).
#[must_use]
pub fn tum_folder(dir: &Path) -> RgbdSequence {
    let src = dir.join("synthetic");
    SyntheticSequence::new(FRAMES, 0.3, 1f64.to_radians())
        .write_tum_rgbd(&src)
        .expect("synthetic");
    let synth = RgbdSequence::open(&src).expect("synthetic folder");
    let out = dir.join("tum");
    for sub in ["rgb", "depth"] {
        std::fs::create_dir_all(out.join(sub)).expect("dir");
    }
    let (mut rgb, mut depth) = (String::new(), String::new());
    for k in 0..FRAMES {
        let (gray, metres) = synth.frame(k).expect("frame");
        gray.save_png(&out.join(format!("rgb/{k}.png")))
            .expect("png");
        let units: Vec<u16> = metres
            .iter()
            .map(|&z| {
                let mm = (f64::from(z) * 1000.0).round();
                if (1.0..13_107.0).contains(&mm) {
                    mm as u16 * 5
                } else {
                    0
                }
            })
            .collect();
        image::ImageBuffer::<image::Luma<u16>, Vec<u16>>::from_raw(
            gray.width as u32,
            gray.height as u32,
            units,
        )
        .expect("depth buffer")
        .save(out.join(format!("depth/{k}.png")))
        .expect("depth png");
        let t = seconds_since(T0_NS, stamp(k));
        rgb.push_str(&format!("{t} rgb/{k}.png\n"));
        depth.push_str(&format!("{t} depth/{k}.png\n"));
    }
    std::fs::write(out.join("rgb.txt"), rgb).expect("rgb.txt");
    std::fs::write(out.join("depth.txt"), depth).expect("depth.txt");
    std::fs::copy(src.join("intrinsics.txt"), out.join("intrinsics.txt")).expect("intrinsics");
    RgbdSequence::open(&out).expect("tum folder")
}

fn header(t: i64) -> Header {
    Header {
        stamp: Time::from_nanos(t),
        frame_id: "camera_color_optical_frame".to_owned(),
    }
}

/// A `camera_info` of an undistorted `w` x `h` camera of intrinsics `[fx, fy, cx, cy]`
/// (pixels) at stamp `t` (ns), CDR.
///
/// # Panics
/// When the message does not encode.
#[must_use]
pub fn info(t: i64, k: [f64; 4], (w, h): (usize, usize)) -> Vec<u8> {
    let [fx, fy, cx, cy] = k;
    encode(&CameraInfo {
        header: header(t),
        width: w as u32,
        height: h as u32,
        distortion_model: "plumb_bob".to_owned(),
        d: vec![0.0; 5],
        k: [fx, 0.0, cx, 0.0, fy, cy, 0.0, 0.0, 1.0],
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [fx, 0.0, cx, 0.0, 0.0, fy, cy, 0.0, 0.0, 0.0, 1.0, 0.0],
        ..CameraInfo::default()
    })
    .expect("encode")
}

/// An image message of `w` x `h` pixels in `encoding` holding `data` (rows of
/// `data.len() / h` bytes) at stamp `t` (ns), CDR.
///
/// # Panics
/// When the message does not encode.
#[must_use]
pub fn image(t: i64, encoding: &str, (w, h): (usize, usize), data: Vec<u8>) -> Vec<u8> {
    encode(&Image {
        header: header(t),
        height: h as u32,
        width: w as u32,
        encoding: encoding.to_owned(),
        is_bigendian: 0,
        step: (data.len() / h.max(1)) as u32,
        data,
    })
    .expect("encode")
}

/// The depth of a frame in `encoding`: `32FC1` metres as they are, else `16UC1`
/// millimetres (little-endian).
#[must_use]
pub fn depth_bytes(metres: &[f32], encoding: &str) -> Vec<u8> {
    match encoding {
        "32FC1" => metres.iter().flat_map(|z| z.to_le_bytes()).collect(),
        _ => metres
            .iter()
            .flat_map(|&z| ((f64::from(z) * 1000.0).round() as u16).to_le_bytes())
            .collect(),
    }
}

/// The four topics of an RGB-D bag, empty: colour, its `camera_info`, depth, its
/// `camera_info`.
fn rgbd_topic_list() -> Vec<TopicData> {
    vec![
        (COLOUR, Image::TYPE, Vec::new()),
        (COLOUR_INFO, CameraInfo::TYPE, Vec::new()),
        (DEPTH, Image::TYPE, Vec::new()),
        (DEPTH_INFO, CameraInfo::TYPE, Vec::new()),
    ]
}

/// The topics of an RGB-D bag of `folder`'s frames (colour as `mono8`), depth in
/// `encoding` (`16UC1` or `32FC1`), stamps [`stamp`]: colour, its `camera_info`, depth,
/// its `camera_info`.
///
/// # Panics
/// When a frame of `folder` cannot be read.
#[must_use]
pub fn rgbd_topics(folder: &RgbdSequence, encoding: &str) -> Vec<TopicData> {
    let k = folder.intrinsics();
    let k = [k.fx, k.fy, k.cx, k.cy];
    let mut topics = rgbd_topic_list();
    for f in 0..folder.len() {
        let (gray, metres) = folder.frame(f).expect("folder frame");
        let (t, size) = (stamp(f), (gray.width, gray.height));
        topics[0].2.push((t, image(t, "mono8", size, gray.data)));
        topics[1].2.push((t, info(t, k, size)));
        let depth = depth_bytes(&metres, encoding);
        topics[2].2.push((t, image(t, encoding, size, depth)));
        topics[3].2.push((t, info(t, k, size)));
    }
    topics
}

/// Writes at `path` a small RGB-D bag: 3 frames of 32 x 24 colour (`mono8`, uniform) and
/// `depth_size` depth images in `depth_encoding` (1 byte a pixel for an encoding other
/// than `16UC1` and `32FC1`), with `camera_info`, and the `extra` topics; returns `path`.
///
/// # Panics
/// When the bag cannot be written.
#[must_use]
pub fn small_bag(
    path: &Path,
    depth_encoding: &str,
    depth_size: (usize, usize),
    extra: &[TopicData],
) -> PathBuf {
    let size = (32, 24);
    let k = [30.0, 30.0, 16.0, 12.0];
    let bpp = match depth_encoding {
        "32FC1" => 4,
        "16UC1" => 2,
        _ => 1,
    };
    let mut topics = rgbd_topic_list();
    for f in 0..3 {
        let t = stamp(f);
        let pixels = vec![128; size.0 * size.1];
        let depth = vec![1; depth_size.0 * depth_size.1 * bpp];
        topics[0].2.push((t, image(t, "mono8", size, pixels)));
        topics[1].2.push((t, info(t, k, size)));
        topics[2]
            .2
            .push((t, image(t, depth_encoding, depth_size, depth)));
        topics[3].2.push((t, info(t, k, depth_size)));
    }
    topics.extend(extra.iter().cloned());
    write_mcap(path, &topics);
    path.to_owned()
}

/// The topics of a second depth camera (`/camera/depth2/...`, one 32 x 24 `16UC1`
/// frame at [`stamp`]`(0)`), to make [`small_bag`] ambiguous.
#[must_use]
pub fn second_depth_camera() -> Vec<TopicData> {
    let t = stamp(0);
    vec![
        (
            "/camera/depth2/image_raw",
            Image::TYPE,
            vec![(t, image(t, "16UC1", (32, 24), vec![0; 32 * 24 * 2]))],
        ),
        (
            "/camera/depth2/camera_info",
            CameraInfo::TYPE,
            vec![(t, info(t, [30.0, 30.0, 16.0, 12.0], (32, 24)))],
        ),
    ]
}
