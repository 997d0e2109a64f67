//! The checks of the ROS 2 fuzz targets: the CDR decoder and the bag front door.

use std::path::PathBuf;

use swarmpose_datasets::StereoSequence;
use swarmpose_ros::bag::parse_metadata;
use swarmpose_ros::msg::{
    CameraInfo, CompressedImage, DiagnosticArray, Image, Odometry, Path, PointCloud2,
    PoseWithCovarianceStamped, RosMessage, TfMessage, decode, decode_header, encode,
};
use swarmpose_ros::{Bag, BagSequence, StereoOptions};

fn round_trip<T: RosMessage>(bytes: &[u8]) {
    if let Ok(m) = decode::<T>(bytes) {
        let again = encode(&m).expect("a decoded message encodes");
        let m2: T = decode(&again).expect("re-encoded bytes decode");
        // NaN != NaN: compare the bytes of a second round trip instead.
        assert_eq!(encode(&m2).expect("encode"), again);
    }
}

/// Any bytes, decoded as the ROS 2 type the first byte selects, give a message or an
/// error, never a panic; a decoded message re-encodes to bytes that decode the same.
pub fn ros_cdr(data: &[u8]) {
    let Some((&which, bytes)) = data.split_first() else {
        return;
    };
    let _ = decode_header(bytes);
    match which % 9 {
        0 => round_trip::<Image>(bytes),
        1 => round_trip::<CompressedImage>(bytes),
        2 => round_trip::<CameraInfo>(bytes),
        3 => round_trip::<PointCloud2>(bytes),
        4 => round_trip::<Odometry>(bytes),
        5 => round_trip::<Path>(bytes),
        6 => round_trip::<PoseWithCovarianceStamped>(bytes),
        7 => round_trip::<TfMessage>(bytes),
        _ => round_trip::<DiagnosticArray>(bytes),
    }
}

fn scratch() -> PathBuf {
    std::env::temp_dir().join(format!(
        "swarmpose-fuzz-ros-bag-{}-{:?}.mcap",
        std::process::id(),
        std::thread::current().id()
    ))
}

/// Any bytes as an `.mcap` file are indexed (a cut or corrupt file gives an error or what
/// it holds whole), every indexed message can be read back, and the stereo search gives a
/// sequence or an error; never a panic. As text, a `metadata.yaml` is parsed too.
pub fn ros_bag(data: &[u8]) {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = parse_metadata(text);
    }
    let path = scratch();
    if std::fs::write(&path, data).is_err() {
        return;
    }
    if let Ok(bag) = Bag::open(&path) {
        for t in bag.topics() {
            for i in 0..t.entries.len() {
                let _ = bag.read(t, i);
            }
        }
    }
    if let Ok(seq) = BagSequence::open(&path, &StereoOptions::default()) {
        for i in 0..seq.len().min(4) {
            let _ = seq.frame(i);
        }
    }
    let _ = std::fs::remove_file(&path);
}
