//! `odometry.mcap` as written by [`swarmpose_ros::write::OdometryMcap`], read back by this
//! crate and by the independent Python `rosbags` package (which parses its `ros2msg`
//! schemas): one message per frame and topic, the same values; a file whose run died
//! before the end is read up to its last whole frame.

mod common;

use serde_json::Value;
use swarmpose_ros::Bag;
use swarmpose_ros::msg::{
    CameraInfo, DiagnosticArray, DiagnosticStatus, Header, Odometry, Pose, PoseStamped, Time,
};
use swarmpose_ros::write::{FrameMessages, OdometryMcap, Topics};

fn frame(k: usize) -> FrameMessages {
    let mut o = Odometry {
        header: Header {
            stamp: Time::from_nanos(1_000_000_000 + k as i64 * 100_000_000),
            frame_id: "odom".to_owned(),
        },
        child_frame_id: "camera_optical".to_owned(),
        ..Odometry::default()
    };
    o.pose.pose.position.x = k as f64 * 0.7;
    o.pose.pose.orientation.w = 1.0;
    o.pose.covariance = std::array::from_fn(|i| {
        if i % 7 == 0 {
            1e-4 * (k + 1) as f64
        } else {
            0.0
        }
    });
    o.twist.twist.linear.x = 7.0;
    FrameMessages {
        odometry: o,
        status: DiagnosticArray {
            header: Header {
                stamp: Time::from_nanos(1_000_000_000 + k as i64 * 100_000_000),
                frame_id: String::new(),
            },
            status: vec![DiagnosticStatus {
                level: DiagnosticStatus::OK,
                name: "swarmpose: tracking".to_owned(),
                message: "tracked".to_owned(),
                ..DiagnosticStatus::default()
            }],
        },
        image: None,
        points: None,
        ground_truth: (k != 3).then(|| {
            let mut g = Pose::default();
            g.position.x = k as f64;
            g.orientation.w = 1.0;
            g
        }),
    }
}

#[test]
fn written_odometry_reads_back_here_and_in_rosbags() {
    let dir = common::scratch("writer");
    let path = dir.join("odometry.mcap");
    let mut w =
        OdometryMcap::new(std::fs::File::create(&path).expect("create"), &path).expect("new");
    w.camera_info(&CameraInfo {
        width: 4,
        height: 3,
        ..CameraInfo::default()
    })
    .expect("info");
    for k in 0..5 {
        w.frame(&frame(k)).expect("frame");
    }
    let truth: Vec<Pose> = (0..5).map(|_| Pose::default()).collect();
    w.finish(Some(&truth)).expect("finish");
    let bag = Bag::open(&path).expect("open");
    assert!(bag.stopped().is_none());
    let odom = bag.topic(Topics::ODOMETRY).expect("odometry topic");
    assert_eq!(odom.entries.len(), 5);
    for k in 0..5 {
        assert_eq!(
            bag.decode::<Odometry>(odom, k).expect("decode"),
            frame(k).odometry
        );
    }
    for (t, n) in [
        (Topics::POSE, 5),
        (Topics::TF, 5),
        (Topics::STATUS, 5),
        (Topics::PATH, 1),
        (Topics::GROUND_TRUTH, 1),
        (Topics::GROUND_TRUTH_POSE, 4),
        (Topics::CAMERA_INFO, 1),
    ] {
        assert_eq!(bag.topic(t).map(|t| t.entries.len()), Some(n), "{t}");
    }
    // Frame 3 has no ground truth: the fourth ground-truth pose is frame 4's.
    let truth = bag.topic(Topics::GROUND_TRUTH_POSE).expect("ground truth");
    let p: PoseStamped = bag.decode(truth, 3).expect("decode");
    assert_eq!(
        (p.pose.position.x, p.header),
        (4.0, frame(4).odometry.header)
    );
    let Some(py) = common::python_with_rosbags() else {
        return;
    };
    let out = dir.join("dump.json");
    common::run_script(&py, "rosbags_dump.py", &[&path, &out]);
    let dump: Value =
        serde_json::from_str(&std::fs::read_to_string(&out).expect("dump")).expect("json");
    assert!(dump.get("error").is_none(), "{dump}");
    let msgs = dump["topics"][Topics::ODOMETRY]["messages"]
        .as_array()
        .expect("odometry");
    assert_eq!(msgs.len(), 5);
    for (k, m) in msgs.iter().enumerate() {
        let theirs = &m[2];
        assert_eq!(
            theirs["pose"]["pose"]["position"]["x"].as_f64(),
            Some(k as f64 * 0.7)
        );
        assert_eq!(
            theirs["pose"]["covariance"][35].as_f64(),
            Some(1e-4 * (k + 1) as f64)
        );
        assert_eq!(theirs["child_frame_id"], "camera_optical");
    }
    let path_msgs = &dump["topics"][Topics::PATH]["messages"];
    assert_eq!(path_msgs[0][2]["poses"].as_array().map(Vec::len), Some(5));
}

#[test]
fn a_run_killed_midway_leaves_every_whole_frame() {
    let dir = common::scratch("writer_killed");
    let path = dir.join("odometry.mcap");
    let mut w =
        OdometryMcap::new(std::fs::File::create(&path).expect("create"), &path).expect("new");
    for k in 0..3 {
        w.frame(&frame(k)).expect("frame");
    }
    // The process dies here: nothing more reaches the file.
    let written = std::fs::read(&path).expect("read");
    std::mem::forget(w);
    let copy = dir.join("killed.mcap");
    std::fs::write(&copy, &written).expect("copy");
    let bag = Bag::open(&copy).expect("open");
    assert!(
        bag.stopped()
            .is_some_and(|s| s.contains("without its summary")),
        "{:?}",
        bag.stopped()
    );
    let odom = bag.topic(Topics::ODOMETRY).expect("odometry");
    assert_eq!(odom.entries.len(), 3);
    assert_eq!(
        bag.decode::<Odometry>(odom, 2).expect("decode"),
        frame(2).odometry
    );
}
