//! RGB-D bags (a colour and a depth `sensor_msgs/Image` topic, each with `camera_info`)
//! written here with the `mcap` crate from the synthetic street rendered with exact
//! depth, and read as the TUM RGB-D folder of the same frames is: the run on the bag
//! gives the folder run's trajectory byte for byte (depth in `32FC1` metres, the folder's
//! values; and in `16UC1` millimetres, the folder's depths being whole millimetres). Bad
//! RGB-D input is refused in one line.

mod common;

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};

use swarmpose_datasets::DepthSequence;
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::{FrameResult, Odometry, OdometryConfig, Status};
use swarmpose_ros::convert::seconds_since;
use swarmpose_ros::msg::{CameraInfo, Header, Image, RosMessage, Time, encode};
use swarmpose_ros::{Input, StereoOptions, open_input};
use swarmpose_runs::batch::{rgbd_camera, run_rgbd_sequence};
use swarmpose_runs::rgbd::RgbdSequence;
use swarmpose_runs::synthetic::SyntheticSequence;

use common::{TopicData, write_mcap};

/// Frames of the clip, the header stamp of the first and the period, nanoseconds.
const FRAMES: usize = 6;
const T0_NS: i64 = 1_305_031_102_000_000_000;
const PERIOD_NS: i64 = 33_333_333;

const COLOUR: &str = "/camera/color/image_raw";
const COLOUR_INFO: &str = "/camera/color/camera_info";
const DEPTH: &str = "/camera/aligned_depth/image_raw";
const DEPTH_INFO: &str = "/camera/aligned_depth/camera_info";

fn stamp(k: usize) -> i64 {
    T0_NS + k as i64 * PERIOD_NS
}

/// A TUM RGB-D folder of the synthetic street whose depths are whole millimetres (5 TUM
/// units each) and whose times are those a bag of stamps [`stamp`] gives (seconds since
/// the first frame), without ground truth.
fn tum_folder(dir: &Path) -> RgbdSequence {
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

fn header(t: i64, frame: &str) -> Header {
    Header {
        stamp: Time::from_nanos(t),
        frame_id: frame.to_owned(),
    }
}

/// A `camera_info` of an undistorted `w` x `h` camera.
fn info(t: i64, k: [f64; 4], (w, h): (usize, usize)) -> Vec<u8> {
    let [fx, fy, cx, cy] = k;
    encode(&CameraInfo {
        header: header(t, "camera_color_optical_frame"),
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

/// An image message of `w` x `h` pixels of `bytes_per_pixel` bytes.
fn image(t: i64, encoding: &str, (w, h): (usize, usize), data: Vec<u8>) -> Vec<u8> {
    encode(&Image {
        header: header(t, "camera_color_optical_frame"),
        height: h as u32,
        width: w as u32,
        encoding: encoding.to_owned(),
        is_bigendian: 0,
        step: (data.len() / h.max(1)) as u32,
        data,
    })
    .expect("encode")
}

/// The depth of a frame in `encoding`: `32FC1` metres as they are, `16UC1` millimetres.
fn depth_bytes(metres: &[f32], encoding: &str) -> Vec<u8> {
    match encoding {
        "32FC1" => metres.iter().flat_map(|z| z.to_le_bytes()).collect(),
        _ => metres
            .iter()
            .flat_map(|&z| ((f64::from(z) * 1000.0).round() as u16).to_le_bytes())
            .collect(),
    }
}

/// The topics of an RGB-D bag of `folder`'s frames, depth in `encoding`.
fn rgbd_topics(folder: &RgbdSequence, encoding: &str) -> Vec<TopicData> {
    let k = folder.intrinsics();
    let k = [k.fx, k.fy, k.cx, k.cy];
    let mut topics: Vec<TopicData> = vec![
        (COLOUR, Image::TYPE, Vec::new()),
        (COLOUR_INFO, CameraInfo::TYPE, Vec::new()),
        (DEPTH, Image::TYPE, Vec::new()),
        (DEPTH_INFO, CameraInfo::TYPE, Vec::new()),
    ];
    for f in 0..FRAMES {
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

fn run(seq: &dyn DepthSequence) -> Vec<FrameResult> {
    let mut odo = Odometry::builder(rgbd_camera(seq).expect("camera"))
        .config(OdometryConfig::default())
        .rgbd(RgbdNoise::default())
        .build()
        .expect("engine");
    let mut out = Vec::new();
    run_rgbd_sequence(seq, &mut odo, &mut |r| {
        out.push(r.clone());
        ControlFlow::Continue(())
    })
    .expect("run");
    out
}

/// The bits of each pose and time of a run.
fn bits(results: &[FrameResult]) -> Vec<Vec<u64>> {
    results
        .iter()
        .map(|r| {
            let m = r.pose.to_homogeneous();
            m.iter()
                .chain(std::iter::once(&r.timestamp_s))
                .map(|x| x.to_bits())
                .collect()
        })
        .collect()
}

fn open_rgbd(path: &Path, opts: &StereoOptions) -> Box<dyn DepthSequence> {
    match open_input(path, opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .input
    {
        Input::Rgbd(seq) => seq,
        Input::Stereo(_) => panic!("{}: opened as stereo", path.display()),
    }
}

#[test]
fn an_rgbd_bag_runs_as_its_folder() {
    let dir = common::scratch("rgbd_bags");
    let folder = tum_folder(&dir);
    let expected = run(&folder);
    assert_eq!(expected.len(), FRAMES);
    assert!(
        expected[1..]
            .iter()
            .all(|r| matches!(r.status, Status::Tracked)),
        "{:?}",
        expected.iter().map(|r| r.status.text()).collect::<Vec<_>>()
    );
    let moved = expected[FRAMES - 1].pose.translation.vector.norm();
    assert!(moved > 0.5, "the camera moved {moved} m");
    for encoding in ["32FC1", "16UC1"] {
        let path = dir.join(format!("rgbd_{encoding}.mcap"));
        write_mcap(&path, &rgbd_topics(&folder, encoding));
        // Found: one colour and one depth camera.
        let bag = open_rgbd(&path, &StereoOptions::default());
        assert_eq!(bag.len(), FRAMES);
        assert_eq!(bag.camera().expect("camera"), folder_camera(&folder));
        for f in 0..FRAMES {
            let (a, b) = (bag.frame(f).expect("bag"), folder.frame(f).expect("folder"));
            assert_eq!((a.gray, a.depth_m), b, "{encoding} frame {f}");
        }
        assert_eq!(bits(&run(bag.as_ref())), bits(&expected), "{encoding}");
        // Named.
        let named = StereoOptions {
            left: Some(COLOUR.to_owned()),
            depth: Some(DEPTH.to_owned()),
            ..StereoOptions::default()
        };
        assert_eq!(open_rgbd(&path, &named).len(), FRAMES);
        eprintln!("{encoding}: {FRAMES} frames, the folder's trajectory to the bit");
    }
}

fn folder_camera(folder: &RgbdSequence) -> (swarmpose_datasets::Intrinsics, (usize, usize)) {
    DepthSequence::camera(folder).expect("folder camera")
}

/// A small RGB-D bag: 3 frames of `size` colour (mono8) and `depth_size` depth images
/// in `encoding`, with `camera_info`, and `extra` topics.
fn small_bag(
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
    let mut topics: Vec<TopicData> = vec![
        (COLOUR, Image::TYPE, Vec::new()),
        (COLOUR_INFO, CameraInfo::TYPE, Vec::new()),
        (DEPTH, Image::TYPE, Vec::new()),
        (DEPTH_INFO, CameraInfo::TYPE, Vec::new()),
    ];
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

fn open_err(path: &Path, opts: &StereoOptions) -> String {
    let e = open_input(path, opts).expect_err("refused").to_string();
    assert!(!e.contains('\n'), "one line: {e}");
    assert!(
        e.starts_with(&path.display().to_string()),
        "names the bag: {e}"
    );
    e
}

#[test]
fn bad_rgbd_input_is_refused_in_one_line() {
    let dir = common::scratch("rgbd_bad");
    let ok = small_bag(&dir.join("ok.mcap"), "32FC1", (32, 24), &[]);
    assert_eq!(open_rgbd(&ok, &StereoOptions::default()).len(), 3);
    // The depth topic named, in a colour encoding.
    let mono = small_bag(&dir.join("mono.mcap"), "mono8", (32, 24), &[]);
    let named = StereoOptions {
        depth: Some(DEPTH.to_owned()),
        ..StereoOptions::default()
    };
    let e = open_err(&mono, &named);
    assert!(
        e.contains(DEPTH) && e.contains("depth encoding 'mono8'") && e.contains("16UC1"),
        "{e}"
    );
    // Depth and colour of different sizes.
    let small = small_bag(&dir.join("size.mcap"), "16UC1", (16, 12), &[]);
    let e = open_err(&small, &StereoOptions::default());
    assert!(
        e.contains("depth images of 16x12 but colour images of 32x24"),
        "{e}"
    );
    // Two depth cameras: ambiguous, the topics listed.
    let t = stamp(0);
    let second: Vec<TopicData> = vec![
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
    ];
    let two = small_bag(&dir.join("two.mcap"), "16UC1", (32, 24), &second);
    let e = open_err(&two, &StereoOptions::default());
    assert!(
        e.contains("2 depth cameras")
            && e.contains("--depth")
            && e.contains(&format!("{DEPTH} (sensor_msgs/msg/Image, 3)")),
        "{e}"
    );
    // A depth topic and a right topic named.
    let both = StereoOptions {
        right: Some(COLOUR.to_owned()),
        depth: Some(DEPTH.to_owned()),
        ..StereoOptions::default()
    };
    let e = open_err(&ok, &both);
    assert!(e.contains("--left and --right for stereo"), "{e}");
}
