//! Bad input, each refused with one clear line: bags written here with the `mcap` crate
//! so that each has exactly one thing wrong.

mod common;

use std::path::{Path, PathBuf};

use swarmpose_ros::msg::{CameraInfo, Header, Image, RosMessage, StringMsg, Time, encode};
use swarmpose_ros::{Bag, BagSequence, RosError, StereoOptions};

use common::{TopicData, write_mcap};

fn image(t: i64, encoding: &str, w: u32, h: u32) -> Vec<u8> {
    let bpp = if encoding == "mono8" { 1 } else { 2 };
    encode(&Image {
        header: Header {
            stamp: Time::from_nanos(t),
            frame_id: "cam".to_owned(),
        },
        height: h,
        width: w,
        encoding: encoding.to_owned(),
        is_bigendian: 0,
        step: w * bpp,
        data: (0..w * h * bpp).map(|i| (i * 7 % 251) as u8).collect(),
    })
    .expect("encode")
}

fn info(t: i64, w: u32, h: u32, tx: f64) -> Vec<u8> {
    encode(&CameraInfo {
        header: Header {
            stamp: Time::from_nanos(t),
            frame_id: "cam".to_owned(),
        },
        width: w,
        height: h,
        distortion_model: "plumb_bob".to_owned(),
        d: vec![0.0; 5],
        k: [500.0, 0.0, 16.0, 0.0, 500.0, 12.0, 0.0, 0.0, 1.0],
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [
            500.0,
            0.0,
            16.0,
            -500.0 * tx,
            0.0,
            500.0,
            12.0,
            0.0,
            0.0,
            0.0,
            1.0,
            0.0,
        ],
        ..CameraInfo::default()
    })
    .expect("encode")
}

/// 3 images of 32x24 pixels in `encoding` at 10 Hz, the first at 1 s + `offset_ns`.
fn images(encoding: &str, offset_ns: i64) -> Vec<(i64, Vec<u8>)> {
    (0..3)
        .map(|k| {
            let t = 1_000_000_000 + offset_ns + k * 100_000_000;
            (t, image(t, encoding, 32, 24))
        })
        .collect()
}

/// Stereo topics of two 32x24 mono8 cameras, 3 frames at 10 Hz, with changes made by
/// `edit` (which gets the topics to alter).
fn stereo(edit: impl FnOnce(&mut Vec<TopicData>)) -> Vec<TopicData> {
    let stamps: Vec<i64> = (0..3).map(|k| 1_000_000_000 + k * 100_000_000).collect();
    let infos = |tx: f64| stamps.iter().map(|&t| (t, info(t, 32, 24, tx))).collect();
    let mut v: Vec<TopicData> = vec![
        ("/cam/left/image_raw", Image::TYPE, images("mono8", 0)),
        ("/cam/left/camera_info", CameraInfo::TYPE, infos(0.0)),
        ("/cam/right/image_raw", Image::TYPE, images("mono8", 0)),
        ("/cam/right/camera_info", CameraInfo::TYPE, infos(0.1)),
    ];
    edit(&mut v);
    v
}

fn open_err(dir: &Path, name: &str, topics: &[TopicData]) -> String {
    let path = dir.join(format!("{name}.mcap"));
    write_mcap(&path, topics);
    let e = BagSequence::open(&path, &StereoOptions::default()).expect_err(name);
    let s = e.to_string();
    assert!(!s.contains('\n'), "{name}: more than one line: {s}");
    assert!(
        s.starts_with(&path.display().to_string()),
        "{name}: names the bag: {s}"
    );
    s
}

fn dir(name: &str) -> PathBuf {
    common::scratch(name)
}

#[test]
fn a_good_bag_opens() {
    let d = dir("bad_input_good");
    let p = d.join("good.mcap");
    write_mcap(&p, &stereo(|_| {}));
    let s = BagSequence::open(&p, &StereoOptions::default()).expect("open");
    assert_eq!(
        s.frames().topics(),
        ("/cam/left/image_raw", "/cam/right/image_raw")
    );
    use swarmpose_datasets::StereoSequence;
    assert_eq!(s.len(), 3);
    assert!((s.calibration().baseline_m - 0.1).abs() < 1e-15);
    assert_eq!(s.timestamp_s(2), Some(0.2));
}

#[test]
fn no_image_topic_lists_what_is_there() {
    let d = dir("bad_input_none");
    let msgs = vec![(5, encode(&StringMsg { data: "hi".into() }).expect("e"))];
    let e = open_err(&d, "none", &[("/chatter", StringMsg::TYPE, msgs)]);
    assert!(
        e.contains("no image topic") && e.contains("/chatter (std_msgs/msg/String, 1)"),
        "{e}"
    );
}

#[test]
fn one_camera_only() {
    let e = open_err(&dir("bad_input_one"), "one", &stereo(|v| v.truncate(2)));
    assert!(e.contains("one camera only (/cam/left/image_raw)"), "{e}");
}

#[test]
fn unsynchronised_stamps() {
    let t = stereo(|v| {
        v[2].2 = images("mono8", 5_000_000);
    });
    let e = open_err(&dir("bad_input_sync"), "sync", &t);
    assert!(
        e.contains("unsynchronised") && e.contains("5.000 ms apart"),
        "{e}"
    );
}

#[test]
fn missing_or_inconsistent_camera_info() {
    let d = dir("bad_input_info");
    let e = open_err(
        &d,
        "missing",
        &stereo(|v| {
            v.remove(3);
            v.remove(1);
        }),
    );
    assert!(e.contains("no camera_info beside the image topics"), "{e}");
    let e = open_err(
        &d,
        "size",
        &stereo(|v| v[3].2 = vec![(1_000_000_000, info(1_000_000_000, 30, 24, 0.1))]),
    );
    assert!(
        e.contains("right camera_info is for 30x24 images but the images are 32x24"),
        "{e}"
    );
    let e = open_err(
        &d,
        "vertical",
        &stereo(|v| v[3].2 = vec![(1_000_000_000, info(1_000_000_000, 32, 24, -0.1))]),
    );
    assert!(e.contains("no horizontal baseline"), "{e}");
    let e = open_err(
        &d,
        "changing",
        &stereo(|v| {
            v[3].2
                .push((1_300_000_000, info(1_300_000_000, 32, 24, 0.2)))
        }),
    );
    assert!(e.contains("message 3 gives another calibration"), "{e}");
}

#[test]
fn unknown_encoding() {
    let t = stereo(|v| {
        v[0].2 = images("yuv422", 0);
    });
    let e = open_err(&dir("bad_input_enc"), "enc", &t);
    assert!(
        e.contains("image encoding 'yuv422' is not one of mono8"),
        "{e}"
    );
}

#[test]
fn corrupt_cdr() {
    let t = stereo(|v| {
        let (t0, bytes) = v[1].2[0].clone();
        v[1].2[0] = (t0, bytes[..bytes.len() - 40].to_vec());
    });
    let e = open_err(&dir("bad_input_cdr"), "cdr", &t);
    assert!(e.contains("/cam/left/camera_info, message 0 (sensor_msgs/msg/CameraInfo): not a sensor_msgs/msg/CameraInfo"), "{e}");
}

#[test]
fn zero_length_bag_and_missing_split_file() {
    let d = dir("bad_input_files");
    let empty = d.join("empty.mcap");
    std::fs::write(&empty, b"").expect("write");
    let e = Bag::open(&empty).expect_err("empty").to_string();
    assert!(e.contains("not an MCAP file (0 bytes"), "{e}");
    let empty_db = d.join("empty.db3");
    std::fs::write(&empty_db, b"").expect("write");
    let e = Bag::open(&empty_db).expect_err("empty db3").to_string();
    assert!(e.contains("empty file (0 bytes)"), "{e}");
    let folder = d.join("split");
    std::fs::create_dir_all(&folder).expect("dir");
    write_mcap(&folder.join("split_0.mcap"), &stereo(|_| {}));
    std::fs::write(
        folder.join("metadata.yaml"),
        "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  relative_file_paths:\n  - split_0.mcap\n  - split_1.mcap\n",
    )
    .expect("yaml");
    let e = Bag::open(&folder).expect_err("missing split").to_string();
    assert!(
        e.contains("metadata.yaml: names") && e.contains("split_1.mcap, which does not exist"),
        "{e}"
    );
    assert!(matches!(Bag::open(&d), Err(RosError::NotABag { .. })));
}
