//! `swarmpose odometry`: bad input gives one clear line (exit 2); on kitti_vo_seq2 the
//! outputs are written and `swarmpose evaluate` on them agrees with the run's summary.

mod common;

use std::path::{Path, PathBuf};

use common::{TempDir, check_error, json_of, swarmpose};
use swarmpose_vision::image::GrayImage;

const CALIB: &str = "P0: 700 0 320 0 0 700 240 0 0 0 1 0\nP1: 700 0 320 -350 0 700 240 0 0 0 1 0\n";
const IDENTITY: &str = "1 0 0 0 0 1 0 0 0 0 1 0\n";

/// A KITTI-layout sequence of `n` blank frames in `dir/name`.
fn kitti_dir(tmp: &TempDir, name: &str, n: usize, poses: Option<&str>) -> PathBuf {
    let dir = tmp.0.join(name);
    for sub in ["image_0", "image_1"] {
        std::fs::create_dir_all(dir.join(sub)).expect("mkdir");
        for i in 0..n {
            GrayImage::new(64, 48)
                .save_png(&dir.join(sub).join(format!("{i:06}.png")))
                .expect("png");
        }
    }
    std::fs::write(dir.join("calib.txt"), CALIB).expect("calib");
    if let Some(p) = poses {
        std::fs::write(dir.join("poses.txt"), p).expect("poses");
    }
    dir
}

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

#[test]
fn bad_sequences_give_one_clear_line() {
    let tmp = TempDir::new("odo-bad");
    let out_dir = tmp.0.join("out");
    let one = kitti_dir(&tmp, "one", 1, None);
    let out = swarmpose(&["odometry", s(&one), "--out", s(&out_dir)], None);
    check_error(&out, &["one", "1 frame(s): odometry needs at least 2"]);

    let short_gt = kitti_dir(&tmp, "short", 3, Some(&IDENTITY.repeat(2)));
    let out = swarmpose(&["odometry", s(&short_gt), "--out", s(&out_dir)], None);
    check_error(&out, &["poses.txt", "2 poses for 3 frames"]);

    let truncated = kitti_dir(
        &tmp,
        "truncated",
        3,
        Some(&format!("{IDENTITY}{IDENTITY}1 0 0 0 0 1 0 0 0 0\n")),
    );
    let out = swarmpose(&["odometry", s(&truncated), "--out", s(&out_dir)], None);
    check_error(&out, &["poses.txt:3", "12 numbers"]);

    let out = swarmpose(
        &["odometry", "/nonexistent/seq", "--out", s(&out_dir)],
        None,
    );
    check_error(&out, &["/nonexistent/seq"]);

    let two = kitti_dir(&tmp, "two", 2, None);
    let out = swarmpose(
        &[
            "odometry",
            s(&two),
            "--out",
            s(&out_dir),
            "--method",
            "svd",
            "--particles",
            "5",
        ],
        None,
    );
    check_error(&out, &["--particles does not apply to --method svd"]);
    assert!(!out_dir.exists(), "nothing written on bad input");
}

#[test]
fn blank_frames_fall_back_visibly() {
    // No texture, no features: every pair falls back, marked in frames.csv, and the
    // run still succeeds with an identity (first pair) that is marked too.
    let tmp = TempDir::new("odo-blank");
    let dir = kitti_dir(&tmp, "blank", 3, None);
    let out_dir = tmp.0.join("out");
    let out = swarmpose(
        &["odometry", s(&dir), "--out", s(&out_dir), "--quiet"],
        None,
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(text.contains("2 constant-velocity frame(s)"), "{text}");
    let csv = std::fs::read_to_string(out_dir.join("frames.csv")).expect("frames.csv");
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 4);
    // rows[0] is the header, rows[1] frame 0.
    assert!(rows[1].contains("first"), "{}", rows[1]);
    assert!(
        rows[2].contains("constant-velocity") && rows[2].contains("identity"),
        "{}",
        rows[2]
    );
    assert!(rows[3].contains("constant-velocity"), "{}", rows[3]);
    for f in [
        "trajectory.kitti.txt",
        "trajectory.tum.txt",
        "trajectory.png",
        "trajectory.svg",
    ] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
}

#[test]
fn kitti_run_writes_its_outputs() {
    let dir = swarmpose_datasets::data_root().join("kitti_vo_seq2");
    if !dir.is_dir() {
        assert!(
            std::env::var("CI").map_or(true, |v| v != "true"),
            "CI=true: {} not found",
            dir.display()
        );
        eprintln!("SKIPPED: {} not found", dir.display());
        return;
    }
    let tmp = TempDir::new("odo-kitti");
    let out_dir = tmp.0.join("out");
    let out = swarmpose(
        &["odometry", s(&dir), "--out", s(&out_dir), "--quiet"],
        None,
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let summary = String::from_utf8(out.stdout).expect("utf-8");
    eprintln!("{summary}");
    for f in [
        "trajectory.kitti.txt",
        "trajectory.tum.txt",
        "frames.csv",
        "trajectory.png",
        "trajectory.svg",
        "errors.png",
        "groundtruth.kitti.txt",
        "evaluation.json",
    ] {
        assert!(out_dir.join(f).is_file(), "{f} missing");
    }
    let csv = std::fs::read_to_string(out_dir.join("frames.csv")).expect("frames.csv");
    assert_eq!(csv.lines().count(), 52);
    let v = json_of(&swarmpose(
        &[
            "evaluate",
            s(&out_dir.join("trajectory.kitti.txt")),
            s(&out_dir.join("groundtruth.kitti.txt")),
            "--json",
        ],
        None,
    ));
    let drift = v["final_drift_percent"].as_f64().expect("drift");
    let rms = v["eq20_rms"].as_f64().expect("rms");
    assert!(summary.contains(&format!("({drift:.3} %)")), "{summary}");
    assert!(
        drift <= 2.0 && rms <= 0.01,
        "drift {drift} %, RMS eq. (20) {rms}"
    );
    // The TUM files give the same ATE.
    let t = json_of(&swarmpose(
        &[
            "evaluate",
            s(&out_dir.join("trajectory.tum.txt")),
            s(&out_dir.join("groundtruth.tum.txt")),
            "--json",
        ],
        None,
    ));
    let (a, b) = (
        v["ate_aligned"]["rmse"].as_f64().expect("ate"),
        t["ate_aligned"]["rmse"].as_f64().expect("ate"),
    );
    assert!((a - b).abs() < 1e-5 * a, "kitti {a} vs tum {b}");
}

#[test]
fn no_sequence_runs_the_built_in_synthetic_one() {
    let tmp = TempDir::new("odo-syn");
    let out_dir = tmp.0.join("out");
    let out = swarmpose(&["odometry", "--out", s(&out_dir), "--quiet"], None);
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("built-in synthetic"), "{stderr}");
    let v = json_of(&swarmpose(
        &[
            "evaluate",
            s(&out_dir.join("trajectory.kitti.txt")),
            s(&out_dir.join("groundtruth.kitti.txt")),
            "--json",
        ],
        None,
    ));
    let drift = v["final_drift_percent"].as_f64().expect("drift");
    assert!(drift < 2.0, "synthetic drift {drift} %");
    assert!(out_dir.join("errors.png").is_file());
}

#[test]
fn tum_rgbd_directory() {
    let tmp = TempDir::new("odo-rgbd");
    let dir = tmp.0.join("rgbd");
    swarmpose_odometry::synthetic::SyntheticSequence::new(6, 0.3, 0.02)
        .write_tum_rgbd(&dir)
        .expect("write");
    let out_dir = tmp.0.join("out");
    let out = swarmpose(
        &["odometry", s(&dir), "--out", s(&out_dir), "--quiet"],
        None,
    );
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        text.contains("TUM RGB-D") && text.contains("final drift"),
        "{text}"
    );
    let tum = std::fs::read_to_string(out_dir.join("trajectory.tum.txt")).expect("tum");
    assert!(tum.starts_with("1305031102.000000 "), "{tum}");
    std::fs::write(dir.join("rgb.txt"), "1305031102.0\n").expect("w");
    let out = swarmpose(&["odometry", s(&dir), "--out", s(&out_dir)], None);
    check_error(&out, &["rgb.txt:1", "timestamp filename"]);
}
