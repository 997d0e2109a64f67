//! `swarmpose odometry` on ROS 2 bags: the first KITTI frames written into bags by the
//! independent Python `rosbags` writer (MCAP plain, MCAP zstd, SQLite; Image mono8 and
//! CompressedImage PNG) give the same trajectory, byte for byte, as the folder of the same
//! frames; `odometry.mcap` holds one Odometry per frame; a cut bag runs its whole frames
//! and exits 2 saying where it stopped.

use std::path::{Path, PathBuf};
use std::process::Command;

use swarmpose_datasets::StereoSequence;
use swarmpose_datasets::kitti::KittiSequence;
use swarmpose_ros::Bag;
use swarmpose_ros::write::Topics;

const FRAMES: usize = 6;

fn python() -> Option<String> {
    let py = std::env::var("SWARMPOSE_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let ok = Command::new(&py)
        .args(["-c", "import rosbags, numpy"])
        .output();
    if ok.is_ok_and(|o| o.status.success()) {
        return Some(py);
    }
    let msg = format!("{py} cannot import rosbags (pip install rosbags, or set SWARMPOSE_PYTHON)");
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true: {msg}"
    );
    eprintln!("SKIPPED: {msg}");
    None
}

fn run(args: &[&Path]) -> std::process::Output {
    Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .arg("odometry")
        .args(args)
        .arg("--quiet")
        .output()
        .expect("run swarmpose")
}

/// A KITTI folder of the first frames (links to the images) and the frames folder the
/// bag maker reads.
fn inputs(kitti: &Path, dir: &Path) -> (PathBuf, PathBuf) {
    let folder = dir.join("kitti");
    let frames = dir.join("frames");
    for d in ["image_0", "image_1"] {
        std::fs::create_dir_all(folder.join(d)).expect("dir");
    }
    std::fs::create_dir_all(&frames).expect("dir");
    std::fs::copy(kitti.join("calib.txt"), folder.join("calib.txt")).expect("calib");
    let calib = std::fs::read_to_string(kitti.join("calib.txt")).expect("calib");
    let row = |key: &str| -> Vec<f64> {
        let line = calib.lines().find(|l| l.starts_with(key)).expect("P row");
        line[key.len()..]
            .split_whitespace()
            .map(|x| x.parse().expect("number"))
            .collect()
    };
    for k in 0..FRAMES {
        for (side, d) in [("left", "image_0"), ("right", "image_1")] {
            let png = kitti.join(d).join(format!("{k:06}.png"));
            std::fs::copy(&png, folder.join(d).join(format!("{k:06}.png"))).expect("png");
            std::fs::copy(&png, frames.join(format!("{side}_{k}.png"))).expect("png");
        }
    }
    let seq = KittiSequence::open(&folder).expect("kitti");
    for k in 0..FRAMES {
        let pair = seq.frame(k).expect("frame");
        std::fs::write(frames.join(format!("left_{k}.raw")), &pair.left.data).expect("raw");
        std::fs::write(frames.join(format!("right_{k}.raw")), &pair.right.data).expect("raw");
    }
    let (w, h) = seq.image_size();
    let meta = serde_json::json!({
        "width": w, "height": h, "p_left": row("P0:"), "p_right": row("P1:"),
        "stamps_ns": (0..FRAMES as i64).map(|k| 1_317_000_000_000_000_000 + k * 100_000_000).collect::<Vec<_>>(),
    });
    std::fs::write(frames.join("meta.json"), meta.to_string()).expect("meta");
    (folder, frames)
}

#[test]
fn a_kitti_bag_gives_the_folder_trajectory_byte_for_byte() {
    let Some(kitti) = swarmpose_datasets::dataset_for_test("kitti_vo_seq2") else {
        return;
    };
    let Some(py) = python() else {
        return;
    };
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join("cli_ros_bags");
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    let (folder, frames) = inputs(&kitti, &dir);
    let out_folder = dir.join("out_folder");
    let o = run(&[&folder, Path::new("--out"), &out_folder]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let want = std::fs::read(out_folder.join("trajectory.kitti.txt")).expect("trajectory");
    let maker =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../swarmpose-ros/tests/py/make_stereo_bag.py");
    for (storage, extra) in [
        ("mcap", None),
        ("mcap-zstd", None),
        ("sqlite3", None),
        ("mcap", Some("png")),
    ] {
        let bag = dir.join(format!("bag_{storage}_{}", extra.unwrap_or("")));
        let mut cmd = Command::new(&py);
        cmd.arg(&maker)
            .arg(&frames)
            .arg(&bag)
            .arg(storage)
            .args(extra);
        let made = cmd.output().expect("python");
        assert!(
            made.status.success(),
            "{}",
            String::from_utf8_lossy(&made.stderr)
        );
        let out = dir.join(format!("out_{storage}_{}", extra.unwrap_or("")));
        let o = run(&[&bag, Path::new("--out"), &out]);
        assert!(
            o.status.success(),
            "{storage}: {}",
            String::from_utf8_lossy(&o.stderr)
        );
        let got = std::fs::read(out.join("trajectory.kitti.txt")).expect("trajectory");
        assert!(
            got == want,
            "{storage} {extra:?}: the trajectory differs from the folder's"
        );
        let mcap = Bag::open(&out.join("odometry.mcap")).expect("odometry.mcap");
        let odom = mcap.topic(Topics::ODOMETRY).expect("odometry topic");
        assert_eq!(odom.entries.len(), FRAMES);
        eprintln!(
            "{storage} {extra:?}: trajectory.kitti.txt identical to the folder's; {FRAMES} Odometry"
        );
    }
    // The same bag cut: its whole frames are run, exit 2 says where it stopped.
    let file = dir.join("bag_mcap_").join("bag_mcap_.mcap");
    let bytes = std::fs::read(&file).expect("bag");
    let cut = dir.join("cut.mcap");
    std::fs::write(&cut, &bytes[..bytes.len() * 6 / 10]).expect("cut");
    let out = dir.join("out_cut");
    let o = run(&[&cut, Path::new("--out"), &out]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.contains("the bag is cut") && stderr.contains("cut at byte"),
        "{stderr}"
    );
    let got = std::fs::read_to_string(out.join("trajectory.kitti.txt")).expect("kept");
    let n = got.lines().count();
    assert!((2..FRAMES).contains(&n), "{n} frames");
    assert!(
        String::from_utf8_lossy(&want).starts_with(&got),
        "the cut run's poses are the folder's"
    );
}
