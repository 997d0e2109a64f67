//! `swarmpose odometry` on ROS 2 bags: the first KITTI frames written into bags by the
//! independent Python `rosbags` writer (MCAP plain, MCAP zstd, SQLite; Image mono8 and
//! CompressedImage PNG) give the same trajectory, byte for byte, as the folder of the same
//! frames; `odometry.mcap` holds one Odometry per frame; a cut bag runs its whole frames
//! and exits 2 saying where it stopped. The first EuRoC frames written as a raw bag (raw
//! images, CameraInfo with K, D, R, P) give the folder's rectified pixels and agree with
//! the folder's run within 1 mm and 0.01 degree.

use std::path::{Path, PathBuf};
use std::process::Command;

use swarmpose_datasets::StereoSequence;
use swarmpose_datasets::euroc::{EurocSequence, read_sensor_yaml};
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

/// The data set `dataset`, the Python with rosbags and a fresh scratch folder `name`;
/// `None` (after saying why) without the data or rosbags.
fn prepare(dataset: &str, name: &str) -> Option<(PathBuf, String, PathBuf)> {
    let data = swarmpose_testdata::dataset_for_test(dataset)?;
    let py = python()?;
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("dir");
    Some((data, py, dir))
}

/// Writes the bag folder `bag` from `frames` with the independent `rosbags` writer.
fn make_bag(py: &str, frames: &Path, bag: &Path, storage: &str, extra: &[&str]) {
    let maker =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../swarmpose-ros/tests/py/make_stereo_bag.py");
    let made = Command::new(py)
        .arg(&maker)
        .args([frames, bag, Path::new(storage)])
        .args(extra)
        .output()
        .expect("python");
    assert!(
        made.status.success(),
        "{}",
        String::from_utf8_lossy(&made.stderr)
    );
}

#[test]
fn a_kitti_bag_gives_the_folder_trajectory_byte_for_byte() {
    let Some((kitti, py, dir)) = prepare("kitti_vo_seq2", "cli_ros_bags") else {
        return;
    };
    let (folder, frames) = inputs(&kitti, &dir);
    let out_folder = dir.join("out_folder");
    let o = run(&[&folder, Path::new("--out"), &out_folder]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let want = std::fs::read(out_folder.join("trajectory.kitti.txt")).expect("trajectory");
    for (storage, extra) in [
        ("mcap", None),
        ("mcap-zstd", None),
        ("sqlite3", None),
        ("mcap", Some("png")),
    ] {
        let bag = dir.join(format!("bag_{storage}_{}", extra.unwrap_or("")));
        make_bag(&py, &frames, &bag, storage, &Vec::from_iter(extra));
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
    a_bag_file_is_a_batch_item_with_tum_ground_truth(&kitti, &dir, &want);
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

/// `swarmpose batch` with the MCAP bag file as its item and the KITTI poses as TUM poses
/// at the bag's header stamps (`ground_truth` in the manifest): the item runs (its input
/// hash is of the file's bytes), its trajectory is the folder's, and its metrics come from
/// the poses matched by time.
fn a_bag_file_is_a_batch_item_with_tum_ground_truth(kitti: &Path, dir: &Path, want: &[u8]) {
    use nalgebra::{Matrix3, Rotation3, UnitQuaternion};
    let mut tum = String::new();
    for (k, m) in kitti_poses(&kitti.join("poses.txt"))
        .iter()
        .take(FRAMES)
        .enumerate()
    {
        let r: Matrix3<f64> = m.fixed_view::<3, 3>(0, 0).into_owned();
        let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&r));
        let stamp_ns = 1_317_000_000_000_000_000_i64 + k as i64 * 100_000_000;
        tum.push_str(&format!(
            "{}.{:09} {} {} {} {} {} {} {}\n",
            stamp_ns / 1_000_000_000,
            stamp_ns % 1_000_000_000,
            m[(0, 3)],
            m[(1, 3)],
            m[(2, 3)],
            q.i,
            q.j,
            q.k,
            q.w
        ));
    }
    std::fs::write(dir.join("truth.tum.txt"), tum).expect("tum");
    let manifest = dir.join("batch.toml");
    std::fs::write(
        &manifest,
        "[[item]]\nname = \"bag\"\ninput = \"bag_mcap_/bag_mcap_.mcap\"\nground_truth = \"truth.tum.txt\"\n",
    )
    .expect("manifest");
    let out = dir.join("out_batch");
    let o = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .arg("batch")
        .args([&manifest, Path::new("--out"), &out])
        .output()
        .expect("swarmpose batch");
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got = std::fs::read(out.join("bag/trajectory.kitti.txt")).expect("trajectory");
    assert!(
        got == want,
        "the batch item's trajectory differs from the folder's"
    );
    let summary: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(out.join("bag/summary.json")).expect("summary"),
    )
    .expect("json");
    let path = summary["metrics"]["path_length_m"]
        .as_f64()
        .expect("metrics");
    assert!(path > 1.0, "{summary}");
}

/// EuRoC frames put in the raw bag.
const EUROC_FRAMES: usize = 10;

/// A EuRoC folder of the first `n` frames of `euroc`, and the frames folder the bag maker
/// reads: the raw images, and each camera's `K`, `D` (plumb_bob), `R` (raw to rectified)
/// and `P` (the rectified camera) as ROS's `CameraInfo` defines them, from the folder's
/// own rectification.
fn euroc_inputs(euroc: &Path, dir: &Path, n: usize) -> (PathBuf, PathBuf) {
    let folder = dir.join("euroc");
    let frames = dir.join("frames");
    std::fs::create_dir_all(&frames).expect("dir");
    for cam in ["cam0", "cam1"] {
        let (src, dst) = (euroc.join("mav0").join(cam), folder.join("mav0").join(cam));
        std::fs::create_dir_all(dst.join("data")).expect("dir");
        std::fs::copy(src.join("sensor.yaml"), dst.join("sensor.yaml")).expect("yaml");
        let list = std::fs::read_to_string(src.join("data.csv")).expect("data.csv");
        let lines: Vec<&str> = list.lines().take(n + 1).collect();
        std::fs::write(dst.join("data.csv"), lines.join("\n") + "\n").expect("data.csv");
        for line in &lines[1..] {
            let name = line.split(',').nth(1).expect("file name").trim();
            std::fs::copy(src.join("data").join(name), dst.join("data").join(name)).expect("png");
        }
    }
    let seq = EurocSequence::open(&folder).expect("euroc");
    for k in 0..n {
        let pair = seq.raw_frame(k).expect("raw frame");
        std::fs::write(frames.join(format!("left_{k}.raw")), &pair.left.data).expect("raw");
        std::fs::write(frames.join(format!("right_{k}.raw")), &pair.right.data).expect("raw");
    }
    let rect = seq.rectification();
    let rig = rect.rig;
    let p = |tx: f64| {
        [
            rig.fx, 0.0, rig.cx, tx, 0.0, rig.fy, rig.cy, 0.0, 0.0, 0.0, 1.0, 0.0,
        ]
    };
    let camera = |cam: &str, r: &nalgebra::Matrix3<f64>| {
        let yaml = folder.join("mav0").join(cam).join("sensor.yaml");
        let c = read_sensor_yaml(&yaml).expect("sensor.yaml").camera;
        serde_json::json!({
            "k": [c.fx, 0.0, c.cx, 0.0, c.fy, c.cy, 0.0, 0.0, 1.0],
            "d": [c.k1, c.k2, c.p1, c.p2, 0.0],
            "r": r.transpose().iter().copied().collect::<Vec<f64>>(),
        })
    };
    let first = seq.raw_frame(0).expect("raw frame").left;
    let meta = serde_json::json!({
        "width": first.width, "height": first.height,
        "p_left": p(0.0), "p_right": p(-rig.fx * rig.baseline_m),
        "stamps_ns": &seq.timestamps_ns()[..n],
        "raw": {"left": camera("cam0", &rect.rect_from_left), "right": camera("cam1", &rect.rect_from_right)},
    });
    std::fs::write(frames.join("meta.json"), meta.to_string()).expect("meta");
    (folder, frames)
}

/// The poses of a KITTI trajectory file.
fn kitti_poses(path: &Path) -> Vec<nalgebra::Matrix4<f64>> {
    std::fs::read_to_string(path)
        .expect("trajectory")
        .lines()
        .map(|l| {
            let v: Vec<f64> = l
                .split_whitespace()
                .map(|x| x.parse().expect("number"))
                .collect();
            let mut m = nalgebra::Matrix4::identity();
            for (k, x) in v.iter().enumerate() {
                m[(k / 4, k % 4)] = *x;
            }
            m
        })
        .collect()
}

#[test]
fn a_raw_euroc_bag_agrees_with_the_folder() {
    let Some((euroc, py, dir)) = prepare("euroc_v1_01_easy_micro", "cli_ros_bags_euroc") else {
        return;
    };
    let (folder, frames) = euroc_inputs(&euroc, &dir, EUROC_FRAMES);
    let bag = dir.join("bag");
    make_bag(&py, &frames, &bag, "mcap", &[]);
    // The bag's rectification (from K, D, R, P) gives the folder's pixels.
    let folder_seq = EurocSequence::open(&folder).expect("euroc");
    let bag_seq = swarmpose_ros::BagSequence::open(&bag, &Default::default()).expect("bag");
    assert!(matches!(
        bag_seq.rig(),
        swarmpose_ros::stereo::calib::Rig::Raw { .. }
    ));
    let (a, b) = (bag_seq.calibration(), folder_seq.calibration());
    assert!((a.baseline_m - b.baseline_m).abs() < 1e-12 && (a.fx, a.cy) == (b.fx, b.cy));
    for k in [0, EUROC_FRAMES - 1] {
        assert_eq!(
            bag_seq.frame(k).expect("bag"),
            folder_seq.frame(k).expect("folder"),
            "frame {k}"
        );
    }
    // The runs agree within 1 mm and 0.01 degree.
    let (out_folder, out_bag) = (dir.join("out_folder"), dir.join("out_bag"));
    for (input, out) in [(&folder, &out_folder), (&bag, &out_bag)] {
        let o = run(&[input, Path::new("--out"), out]);
        assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    }
    let want = kitti_poses(&out_folder.join("trajectory.kitti.txt"));
    let got = kitti_poses(&out_bag.join("trajectory.kitti.txt"));
    assert_eq!((want.len(), got.len()), (EUROC_FRAMES, EUROC_FRAMES));
    let (mut dt, mut dr) = (0.0f64, 0.0f64);
    for (w, g) in want.iter().zip(&got) {
        dt = dt.max((w.fixed_view::<3, 1>(0, 3) - g.fixed_view::<3, 1>(0, 3)).norm());
        let r = w.fixed_view::<3, 3>(0, 0).transpose() * g.fixed_view::<3, 3>(0, 0);
        dr = dr.max(
            ((r.trace() - 1.0) / 2.0)
                .clamp(-1.0, 1.0)
                .acos()
                .to_degrees(),
        );
    }
    eprintln!(
        "EuRoC raw bag vs folder: {EUROC_FRAMES} frames, largest difference {dt:.3e} m, {dr:.3e} deg"
    );
    assert!(dt <= 1e-3 && dr <= 0.01, "{dt} m, {dr} deg");
}

#[test]
fn images_without_a_partner_are_counted_and_named() {
    let Some((kitti, py, dir)) = prepare("kitti_vo_seq2", "cli_ros_bags_unpaired") else {
        return;
    };
    let (_, frames) = inputs(&kitti, &dir);
    let bag = dir.join("bag");
    // Frame 2 has no right image and frame 4 no left one.
    make_bag(&py, &frames, &bag, "mcap", &["drop=right:2", "drop=left:4"]);
    let out = dir.join("out");
    let o = run(&[&bag, Path::new("--out"), &out]);
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let (left, right) = (
        "/stereo/left/image_rect message 2 (stamp 1317000000200000000 ns)",
        "/stereo/right/image_rect message 3 (stamp 1317000000400000000 ns)",
    );
    assert!(
        stdout.contains("2 image(s) without a partner")
            && stdout.contains(left)
            && stdout.contains(right),
        "{stdout}"
    );
    let csv = std::fs::read_to_string(out.join("frames.csv")).expect("frames.csv");
    // Every row has the header's fields (the reader checks it).
    let rows: Vec<csv::StringRecord> = csv::Reader::from_reader(csv.as_bytes())
        .records()
        .map(|r| r.expect("a row with the header's fields"))
        .collect();
    let described: Vec<(&str, &str, &str)> = rows.iter().map(|r| (&r[0], &r[1], &r[2])).collect();
    assert_eq!(described.len(), 6, "{csv}");
    assert_eq!(
        (described[2], described[4]),
        (
            ("", "0.200000", &*format!("unpaired ({left})")),
            ("", "0.400000", &*format!("unpaired ({right})"))
        ),
        "{csv}"
    );
    let frame_numbers: Vec<&str> = described
        .iter()
        .map(|d| d.0)
        .filter(|f| !f.is_empty())
        .collect();
    assert_eq!(frame_numbers, ["0", "1", "2", "3"]);
    let poses = std::fs::read_to_string(out.join("trajectory.kitti.txt")).expect("trajectory");
    assert_eq!(poses.lines().count(), 4);
}
