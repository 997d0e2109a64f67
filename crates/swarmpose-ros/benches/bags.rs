//! Speed of the ROS 2 input and output, one thread:
//!
//! - `run/*`: what a run does with the first KITTI frames (`kitti_vo_seq2`, 1241 x 376):
//!   open the input, then read every frame once, in order; from the folder (two PNGs
//!   decoded a frame) and from bags of the same frames (`sensor_msgs/Image` mono8 with
//!   `camera_info`, as `ros2 bag record` writes them: MCAP with chunks uncompressed and
//!   with zstd, and SQLite `.db3`). The zstd bag is also read with no decompressed chunk
//!   kept between opening and reading but the last (`bag_mcap_zstd_uncached`): what a
//!   frame of a bag much longer than the chunk cache costs. `open/*`: the opening alone
//!   (the index, every image's header stamp, every `camera_info`, the first frame for the
//!   image size).
//! - `write/odometry_mcap_frame`: one frame of `odometry.mcap` without images (Odometry,
//!   PoseWithCovarianceStamped, /tf, DiagnosticArray, ground-truth pose; one zstd chunk
//!   flushed to the file).
//!
//! Needs `kitti_vo_seq2` under the data root (`SWARMPOSE_DATA`); skipped with a message
//! otherwise. `tools/ros_bench/results.py` runs it and writes RESULTS.md's table.
//!
//! `cargo bench -p swarmpose-ros --bench bags`

use std::collections::BTreeMap;
use std::fs::File;
use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{Criterion, criterion_group, criterion_main};
use mcap::Compression;
use nalgebra::{Isometry3, Matrix6, Translation3, UnitQuaternion};
use swarmpose_datasets::{StereoSequence, open};
use swarmpose_ros::convert::{FrameNames, Measurement, odometry};
use swarmpose_ros::msg::{
    CameraInfo, DiagnosticArray, DiagnosticStatus, Header, Image, Pose, RosMessage, Time, encode,
};
use swarmpose_ros::write::{FrameMessages, OdometryMcap};
use swarmpose_ros::{Bag, BagSequence, StereoOptions};
use swarmpose_testdata::bags::write_mcap_messages;

/// Frames of the clip.
const FRAMES: usize = 10;

fn scratch() -> PathBuf {
    let dir = std::env::temp_dir().join(format!("swarmpose-bench-bags-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

/// The `camera_info` of a side of the rectified rig.
fn camera_info(seq: &dyn StereoSequence, right: bool, header: Header) -> CameraInfo {
    let c = seq.calibration();
    let (w, h) = seq.image_size();
    let tx = if right { -c.fx * c.baseline_m } else { 0.0 };
    CameraInfo {
        header,
        width: w as u32,
        height: h as u32,
        distortion_model: "plumb_bob".to_owned(),
        d: vec![0.0; 5],
        k: [c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0],
        r: [1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0],
        p: [
            c.fx, 0.0, c.cx, tx, 0.0, c.fy, c.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
        ],
        ..CameraInfo::default()
    }
}

/// A bag's messages: topic, type, log time (ns) and bytes.
type Messages = Vec<(String, &'static str, i64, Vec<u8>)>;

/// The messages of the first [`FRAMES`] frames of `seq`, as a stereo camera driver
/// publishes them: per frame and side, the image and its `camera_info`.
fn messages(seq: &dyn StereoSequence) -> Messages {
    let mut out = Vec::new();
    for k in 0..FRAMES {
        let pair = seq.frame(k).expect("frame");
        let t = 1_317_000_000_000_000_000 + k as i64 * 100_000_000;
        for (side, (name, img)) in ["left", "right"]
            .iter()
            .zip([pair.left, pair.right])
            .enumerate()
        {
            let header = Header {
                stamp: Time::from_nanos(t),
                frame_id: format!("camera_{side}_optical"),
            };
            let image = Image {
                header: header.clone(),
                width: img.width as u32,
                height: img.height as u32,
                encoding: "mono8".to_owned(),
                is_bigendian: 0,
                step: img.width as u32,
                data: img.data,
            };
            let info = camera_info(seq, side == 1, header);
            out.push((
                format!("/stereo/{name}/image_rect"),
                Image::TYPE,
                t,
                encode(&image).expect("cdr"),
            ));
            out.push((
                format!("/stereo/{name}/camera_info"),
                CameraInfo::TYPE,
                t,
                encode(&info).expect("cdr"),
            ));
        }
    }
    out
}

/// Writes `messages` as an MCAP bag at `path` (swarmpose-testdata's writer).
fn write_mcap(messages: &Messages, path: &Path, compression: Option<Compression>) {
    write_mcap_messages(
        path,
        messages
            .iter()
            .map(|(topic, ty, t, data)| (topic.as_str(), *ty, *t, data.as_slice())),
        compression,
    );
}

/// Writes `messages` as a rosbag2 SQLite file at `path` (the tables `ros2 bag record`
/// writes, without the QoS and metadata columns the reader does not use).
fn write_db3(messages: &Messages, path: &Path) {
    let _ = std::fs::remove_file(path);
    let mut db = rusqlite::Connection::open(path).expect("db3");
    db.execute_batch(
        "CREATE TABLE topics(id INTEGER PRIMARY KEY, name TEXT NOT NULL, type TEXT NOT NULL, \
         serialization_format TEXT NOT NULL, offered_qos_profiles TEXT NOT NULL); \
         CREATE TABLE messages(id INTEGER PRIMARY KEY, topic_id INTEGER NOT NULL, \
         timestamp INTEGER NOT NULL, data BLOB NOT NULL);",
    )
    .expect("tables");
    let tx = db.transaction().expect("transaction");
    let mut ids: BTreeMap<String, i64> = BTreeMap::new();
    for (topic, ty, t, data) in messages {
        let next = ids.len() as i64 + 1;
        let id = *ids.entry(topic.clone()).or_insert_with(|| {
            tx.execute(
                "INSERT INTO topics VALUES (?1, ?2, ?3, 'cdr', '')",
                rusqlite::params![next, topic, ty],
            )
            .expect("topic");
            next
        });
        tx.execute(
            "INSERT INTO messages(topic_id, timestamp, data) VALUES (?1, ?2, ?3)",
            rusqlite::params![id, t, data],
        )
        .expect("message");
    }
    tx.commit().expect("commit");
}

/// The runs on bags: bench name, bag, chunk cache budget (`None`: the default). The zstd
/// bag is also read with no chunk kept but the last (`Some(0)`): what a frame of a bag
/// much longer than the cache costs.
const RUNS: [(&str, &str, Option<usize>); 4] = [
    ("bag_mcap", "mcap", None),
    ("bag_mcap_zstd", "mcap_zstd", None),
    ("bag_mcap_zstd_uncached", "mcap_zstd", Some(0)),
    ("bag_db3", "db3", None),
];

fn bag_path(dir: &Path, name: &str) -> PathBuf {
    dir.join(match name {
        "db3" => "db3.db3".to_owned(),
        _ => format!("{name}.mcap"),
    })
}

/// Opens the bag `name` of `dir` as a run does (`cache_bytes`: the bag's budget of kept
/// decompressed chunks, `None` for the default).
fn open_bag(dir: &Path, name: &str, cache_bytes: Option<usize>) -> BagSequence {
    let mut bag = Bag::open(&bag_path(dir, name)).expect("bag");
    if let Some(bytes) = cache_bytes {
        bag.set_chunk_cache_bytes(bytes);
    }
    BagSequence::from_bag(bag, &StereoOptions::default()).expect("stereo bag")
}

/// Every frame of `seq`, in order, as a run reads them.
fn read_all(seq: &dyn StereoSequence) {
    for k in 0..seq.len() {
        black_box(seq.frame(k).expect("frame"));
    }
}

fn bench_read(c: &mut Criterion, kitti: &Path, seq: &dyn StereoSequence, dir: &Path) {
    let msgs = messages(seq);
    write_mcap(&msgs, &dir.join("mcap.mcap"), None);
    write_mcap(&msgs, &dir.join("mcap_zstd.mcap"), Some(Compression::Zstd));
    write_db3(&msgs, &dir.join("db3.db3"));
    // A run: open the input, then read every frame once, in order.
    let mut g = c.benchmark_group("run");
    g.sample_size(10);
    g.bench_function("folder", |b| {
        b.iter(|| {
            let seq = open(kitti).expect("folder");
            for k in 0..FRAMES {
                black_box(seq.frame(k).expect("frame"));
            }
        });
    });
    for (label, name, cache) in RUNS {
        assert_eq!(open_bag(dir, name, cache).len(), FRAMES);
        g.bench_function(label, |b| b.iter(|| read_all(&open_bag(dir, name, cache))));
    }
    g.finish();
    // Of which opening (index, header stamps, camera_info, the first frame for its size).
    let mut g = c.benchmark_group("open");
    g.sample_size(10);
    for (label, name, cache) in RUNS {
        g.bench_function(label, |b| b.iter(|| black_box(open_bag(dir, name, cache))));
    }
    g.finish();
}

/// A frame's messages as a run writes them: a tracked frame with a covariance.
fn frame_messages(k: usize) -> FrameMessages {
    let pose = Isometry3::from_parts(
        Translation3::new(0.01 * k as f64, 0.0, 0.8 * k as f64),
        UnitQuaternion::from_euler_angles(0.0, 0.002 * k as f64, 0.0),
    );
    let m = Measurement {
        motion: Isometry3::translation(0.0, 0.0, 0.8),
        covariance: Some(Matrix6::from_fn(|i, j| if i == j { 1e-4 } else { 1e-6 })),
        dt_s: 0.1,
    };
    let stamp = 1_000_000_000 + k as i64 * 100_000_000;
    let odom = odometry(stamp, &pose, k == 0, Some(&m), &FrameNames::default());
    FrameMessages {
        status: DiagnosticArray {
            header: odom.header.clone(),
            status: vec![DiagnosticStatus {
                level: DiagnosticStatus::OK,
                name: "swarmpose: tracking".to_owned(),
                message: "tracked".to_owned(),
                ..DiagnosticStatus::default()
            }],
        },
        ground_truth: Some(odom.pose.pose),
        odometry: odom,
        image: None,
        points: None,
    }
}

fn bench_write(c: &mut Criterion, dir: &Path) {
    let path = dir.join("odometry.mcap");
    let mut w = OdometryMcap::new(File::create(&path).expect("file"), &path).expect("writer");
    let mut g = c.benchmark_group("write");
    g.sample_size(20);
    let mut k = 0;
    g.bench_function("odometry_mcap_frame", |b| {
        b.iter(|| {
            k += 1;
            w.frame(black_box(&frame_messages(k))).expect("frame");
        });
    });
    g.finish();
    w.finish(Some(&vec![Pose::default(); k])).expect("finish");
}

fn bench_bags(c: &mut Criterion) {
    let kitti = swarmpose_testdata::data_root().join("kitti_vo_seq2");
    let Ok(seq) = open(&kitti) else {
        eprintln!(
            "SKIPPED: {} not found (set SWARMPOSE_DATA)",
            kitti.display()
        );
        return;
    };
    let dir = scratch();
    bench_read(c, &kitti, seq.as_ref(), &dir);
    bench_write(c, &dir);
    let _ = std::fs::remove_dir_all(&dir);
}

criterion_group!(benches, bench_bags);
criterion_main!(benches);
