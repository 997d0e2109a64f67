//! `swarmpose odometry`: bad input gives one clear line (exit 2); on kitti_vo_seq2 the
//! outputs are written and `swarmpose evaluate` on them agrees with the run's summary.

use std::path::PathBuf;

use crate::common::{TempDir, assert_success, check_error, evaluate_json, odometry, s, swarmpose};
use swarmpose_vision::image::GrayImage;

const CALIB: &str = "P0: 700 0 32 0 0 700 24 0 0 0 1 0\nP1: 700 0 32 -350 0 700 24 0 0 0 1 0\n";
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
    // Each: options after `odometry TWO --out OUT`, and what the one line must say.
    let max = usize::MAX.to_string();
    let quarter = (usize::MAX / 4).to_string();
    let too_many = format!("min_working_pixels {quarter}: at most 16777216");
    let mut cases: Vec<(Vec<&str>, Vec<String>)> = vec![
        (
            vec!["--method", "svd", "--particles", "5"],
            vec!["--particles does not apply to --method svd".into()],
        ),
        (
            vec!["--max-working-pixels", "5"],
            vec!["max_working_pixels 5: at least 10000 are needed".into()],
        ),
        // Images doubled without end: the process was killed for want of memory.
        (
            vec![
                "--max-working-pixels",
                &max,
                "--min-working-pixels",
                &quarter,
            ],
            vec![too_many],
        ),
    ];
    // Fewer than 3 inliers were raised to 3 without a word (Python refuses them).
    for n in ["0", "2", "-1"] {
        cases.push((
            vec!["--min-inliers", n],
            vec![
                format!("'{n}' for '--min-inliers <N>'"),
                "at least 3 are needed".into(),
            ],
        ));
    }
    // The guided search's radius is a distance.
    for r in ["0", "-3", "nan"] {
        cases.push((
            vec!["--guided-radius", r],
            vec![
                format!("'{r}' for '--guided-radius <PX>'"),
                "a finite number of pixels above 0".into(),
            ],
        ));
    }
    for (options, expected) in &cases {
        let mut args = vec!["odometry", s(&two), "--out", s(&out_dir)];
        args.extend(options);
        let out = swarmpose(&args, None);
        let expected: Vec<&str> = expected.iter().map(String::as_str).collect();
        check_error(&out, &expected);
    }
    assert!(!out_dir.exists(), "nothing written on bad input");
}

#[test]
fn blank_frames_are_not_usable_but_written() {
    // No texture, no features: no motion can be tracked. Every frame is written, marked
    // lost, and the run exits with the "not usable" status.
    let tmp = TempDir::new("odo-blank");
    let dir = kitti_dir(&tmp, "blank", 12, None);
    let out_dir = tmp.0.join("out");
    let out = odometry(Some(&dir), &out_dir, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(
        stderr.starts_with("swarmpose: error: not usable: 0 motions of 11 were tracked"),
        "{stderr}"
    );
    let text = String::from_utf8(out.stdout).expect("utf-8");
    assert!(
        text.contains("12 frames: 0 of 11 motions tracked, 0 at constant velocity, 12 lost"),
        "{text}"
    );
    let traj = std::fs::read_to_string(out_dir.join("trajectory.kitti.txt")).expect("trajectory");
    assert_eq!(traj.lines().count(), 12);
    let csv = std::fs::read_to_string(out_dir.join("frames.csv")).expect("frames.csv");
    let rows: Vec<&str> = csv.lines().collect();
    assert_eq!(rows.len(), 13);
    // rows[0] is the header, rows[1] frame 0.
    assert!(rows[1].contains("lost (0 stereo points"), "{}", rows[1]);
    assert!(rows[2].contains("lost ("), "{}", rows[2]);
    for f in [
        "trajectory.kitti.txt",
        "trajectory.tum.txt",
        "trajectory.png",
        "trajectory.svg",
        "calibration.json",
    ] {
        assert!(out_dir.join(f).is_file(), "{f}");
    }
}

/// A KITTI-layout sequence of `n` copies of one rendered synthetic stereo pair (a camera
/// standing still), with the calibration of the synthetic rig.
fn still_sequence(tmp: &TempDir, n: usize) -> PathBuf {
    use swarmpose_datasets::StereoSequence;
    use swarmpose_runs::synthetic::{RIG, SyntheticSequence};
    let dir = tmp.0.join("still");
    let pair = SyntheticSequence::new(1, 0.0, 0.0)
        .frame(0)
        .expect("render");
    for (sub, img) in [("image_0", &pair.left), ("image_1", &pair.right)] {
        std::fs::create_dir_all(dir.join(sub)).expect("mkdir");
        for i in 0..n {
            img.save_png(&dir.join(sub).join(format!("{i:06}.png")))
                .expect("png");
        }
    }
    let p = |tx: f64| {
        format!(
            "{} 0 {} {tx} 0 {} {} 0 0 0 1 0",
            RIG.fx, RIG.cx, RIG.fy, RIG.cy
        )
    };
    std::fs::write(
        dir.join("calib.txt"),
        format!("P0: {}\nP1: {}\n", p(0.0), p(-RIG.fx * RIG.baseline_m)),
    )
    .expect("calib");
    dir
}

#[test]
fn a_corrupt_frame_stops_the_run_and_keeps_what_came_before() {
    let tmp = TempDir::new("odo-corrupt");
    let dir = still_sequence(&tmp, 36);
    let bad = dir.join("image_0").join("000030.png");
    std::fs::write(&bad, b"\x89PNG\r\n\x1a\nnot really a png").expect("corrupt");
    let out_dir = tmp.0.join("out");
    let out = odometry(Some(&dir), &out_dir, &[]);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(
        stderr.starts_with("swarmpose: error: frame 30: ") && stderr.contains("000030.png"),
        "{stderr}"
    );
    assert!(stderr.contains("stopped after 30 frame(s)"), "{stderr}");
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    let traj = std::fs::read_to_string(out_dir.join("trajectory.kitti.txt")).expect("trajectory");
    assert_eq!(traj.lines().count(), 30);
    let tum = std::fs::read_to_string(out_dir.join("trajectory.tum.txt")).expect("tum");
    assert_eq!(tum.lines().count(), 30);
    let csv = std::fs::read_to_string(out_dir.join("frames.csv")).expect("frames.csv");
    assert_eq!(csv.lines().count(), 31);
    // The camera stands still: every pose is the origin to a millimetre.
    for line in traj.lines() {
        let v: Vec<f64> = line
            .split_whitespace()
            .map(|x| x.parse().expect("number"))
            .collect();
        assert!(
            v[3].abs() < 1e-3 && v[7].abs() < 1e-3 && v[11].abs() < 1e-3,
            "{line}"
        );
    }
}

/// The command line is a loop over the library's engine: the same trajectory, line for
/// line, as the engine driven directly.
#[test]
fn the_cli_gives_the_engine_s_trajectory() {
    use swarmpose_odometry::{Odometry, OdometryConfig};
    use swarmpose_runs::batch::{camera_of, collect};
    use swarmpose_runs::output::kitti_line;
    use swarmpose_runs::synthetic::SyntheticSequence;
    let tmp = TempDir::new("odo-same");
    let out_dir = tmp.0.join("out");
    let out = odometry(None, &out_dir, &[]);
    assert_success(&out);
    let cli = std::fs::read_to_string(out_dir.join("trajectory.kitti.txt")).expect("trajectory");
    let seq = SyntheticSequence::default();
    let mut odo = Odometry::new(camera_of(&seq), OdometryConfig::default()).expect("engine");
    let results = collect(&seq, &mut odo, 0.1).expect("run");
    let engine: String = results
        .iter()
        .map(|r| format!("{}\n", kitti_line(&r.pose)))
        .collect();
    assert_eq!(cli, engine);
}

#[test]
fn kitti_run_writes_its_outputs() {
    let Some(dir) = crate::common::shared_dataset("kitti_vo_seq2") else {
        return;
    };
    let tmp = TempDir::new("odo-kitti");
    let out_dir = tmp.0.join("out");
    let out = odometry(Some(&dir), &out_dir, &[]);
    assert_success(&out);
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
    // Every row has the header's fields (a status with a comma is quoted), and the
    // correction's terms are where the header says.
    let mut reader = csv::Reader::from_reader(csv.as_bytes());
    let header = reader.headers().expect("header").clone();
    let column = |name: &str| header.iter().position(|h| h == name).expect(name);
    let rows: Vec<csv::StringRecord> = reader
        .records()
        .map(|r| r.expect("a row with the header's fields"))
        .collect();
    let last = rows.last().expect("a row");
    for term in [
        "correction_offset_px",
        "correction_quadratic_px",
        "correction_linear_px",
    ] {
        let v: f64 = last[column(term)].parse().expect("a number");
        assert!(v.is_finite() && v.abs() < 10.0, "{term} {v}");
    }
    // The window's last estimate of every frame, and its evaluation.
    let smoothed =
        std::fs::read_to_string(out_dir.join("trajectory.smoothed.kitti.txt")).expect("smoothed");
    assert_eq!(smoothed.lines().count(), 51);
    assert!(
        summary.contains("smoothed (each frame's last window estimate)"),
        "{summary}"
    );
    let v = evaluate_json(&out_dir, "trajectory.kitti.txt", "groundtruth.kitti.txt");
    let drift = v["final_drift_percent"].as_f64().expect("drift");
    let rms = v["eq20_rms"].as_f64().expect("rms");
    assert!(summary.contains(&format!("({drift:.3} %)")), "{summary}");
    assert!(
        drift <= 2.0 && rms <= 0.01,
        "drift {drift} %, RMS eq. (20) {rms}"
    );
    // The TUM files give the same ATE.
    let t = evaluate_json(&out_dir, "trajectory.tum.txt", "groundtruth.tum.txt");
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
    let out = odometry(None, &out_dir, &[]);
    assert_success(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(stderr.contains("built-in synthetic"), "{stderr}");
    let v = evaluate_json(&out_dir, "trajectory.kitti.txt", "groundtruth.kitti.txt");
    let drift = v["final_drift_percent"].as_f64().expect("drift");
    assert!(drift < 2.0, "synthetic drift {drift} %");
    assert!(out_dir.join("errors.png").is_file());
}

#[test]
fn tum_rgbd_directory() {
    let tmp = TempDir::new("odo-rgbd");
    let dir = tmp.0.join("rgbd");
    swarmpose_runs::synthetic::SyntheticSequence::new(6, 0.3, 0.02)
        .write_tum_rgbd(&dir)
        .expect("write");
    let out_dir = tmp.0.join("out");
    let out = odometry(Some(&dir), &out_dir, &[]);
    assert_success(&out);
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

/// SIGTERM half-way: the run stops between two frames, keeps the poses so far (whole
/// lines), writes the summary and exits with 143.
#[test]
fn sigterm_keeps_the_frames_so_far() {
    use std::process::{Command, Stdio};
    use std::time::{Duration, Instant};
    let tmp = TempDir::new("odo-term");
    let dir = still_sequence(&tmp, 400);
    let out_dir = tmp.0.join("out");
    let child = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .args(["odometry", s(&dir), "--out", s(&out_dir), "--quiet"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run swarmpose");
    // Wait until some frames are written, then ask it to stop.
    let traj = out_dir.join("trajectory.kitti.txt");
    let start = Instant::now();
    while std::fs::read_to_string(&traj).map_or(0, |t| t.lines().count()) < 5 {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "no frame written"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let killed = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .expect("kill");
    assert!(killed.success());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(143), "{stderr}");
    assert!(stderr.contains("stopped by SIGTERM after"), "{stderr}");
    let lines = std::fs::read_to_string(&traj).expect("trajectory");
    assert!(lines.ends_with('\n'), "whole lines only");
    let n = lines.lines().count();
    assert!((5..400).contains(&n), "{n} poses");
    for line in lines.lines() {
        assert_eq!(line.split_whitespace().count(), 12, "{line}");
    }
    let csv = std::fs::read_to_string(out_dir.join("frames.csv")).expect("frames.csv");
    assert_eq!(csv.lines().count(), n + 1);
    let summary = String::from_utf8_lossy(&out.stdout);
    assert!(summary.contains(&format!("{n} frames: ")), "{summary}");
    assert!(out_dir.join("calibration.json").is_file());
}

/// A closed or full standard output never panics.
#[test]
fn closed_and_full_standard_output() {
    use std::process::{Command, Stdio};
    let tmp = TempDir::new("odo-pipe");
    let out_dir = tmp.0.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .args(["odometry", "--out", s(&out_dir), "--quiet"])
        .env("RUST_BACKTRACE", "1")
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run swarmpose");
    // Close the reading end at once: the summary meets a broken pipe.
    drop(child.stdout.take());
    let out = child.wait_with_output().expect("wait");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        !stderr.contains("panicked") && !stderr.contains("internal error"),
        "{stderr}"
    );
    assert_eq!(out.status.code(), Some(141), "{stderr}");
    if std::path::Path::new("/dev/full").exists() {
        let full = std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full");
        let out = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
            .args(["odometry", "--out", s(&out_dir), "--quiet"])
            .stdout(full)
            .output()
            .expect("run");
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{stderr}");
        assert!(
            stderr.contains("cannot write to standard output"),
            "{stderr}"
        );
    }
}

#[test]
fn a_run_s_configuration_reruns_it_byte_for_byte() {
    let tmp = TempDir::new("odo-config");
    let run = |name: &str, options: &[&str]| {
        let dir = tmp.0.join(name);
        let mut args = vec!["odometry", "--out", s(&dir), "--quiet"];
        args.extend_from_slice(options);
        let out = swarmpose(&args, None);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        dir
    };
    let first = run(
        "first",
        &[
            "--window",
            "3",
            "--seed",
            "7",
            "--particles",
            "20",
            "--calibration-memory",
            "inf",
        ],
    );
    let config = first.join("config.json");
    let text = std::fs::read_to_string(&config).expect("config.json");
    assert!(text.contains(r#""memory_s": "inf""#), "{text}");
    assert!(text.contains(r#""swarm_size": 20"#), "{text}");

    let second = run("second", &["--config", s(&config)]);
    for name in [
        "config.json",
        "trajectory.kitti.txt",
        "motion_covariance.csv",
    ] {
        let a = std::fs::read(first.join(name)).expect("first");
        let b = std::fs::read(second.join(name)).expect("second");
        assert!(a == b, "{name} differs between the run and its rerun");
    }
    // An option beside the file replaces its setting.
    let third = run(
        "third",
        &[
            "--config",
            s(&config),
            "--seed",
            "8",
            "--guided-radius",
            "20",
        ],
    );
    let text = std::fs::read_to_string(third.join("config.json")).expect("third");
    assert!(text.contains(r#""seed": 8"#) && text.contains(r#""swarm_size": 20"#));
    assert!(text.contains(r#""guided_radius_px": 20.0"#), "{text}");
    assert!(!text.contains(r#""guided_radius_px": null"#), "{text}");

    let bad = tmp.0.join("bad.json");
    std::fs::write(&bad, r#"{"odometry": {"window": {"keyframes": "ten"}}}"#).expect("bad");
    let out = swarmpose(
        &[
            "odometry",
            "--out",
            s(&tmp.0.join("bad")),
            "--config",
            s(&bad),
        ],
        None,
    );
    check_error(
        &out,
        &["bad.json: configuration: invalid type", "expected usize"],
    );
    // A value of the right type outside its range: named, before the first frame.
    let range = tmp.0.join("range.json");
    std::fs::write(
        &range,
        r#"{"odometry": {"orb": {"stereo": {"row_tolerance_px": -1.0}}}}"#,
    )
    .expect("range");
    let out = swarmpose(
        &[
            "odometry",
            "--out",
            s(&tmp.0.join("range")),
            "--config",
            s(&range),
        ],
        None,
    );
    check_error(
        &out,
        &[
            "range.json: configuration: orb.stereo.row_tolerance_px is -1: it must be a \
           finite number, 0 or more",
        ],
    );
    // The estimator's settings too, before the first frame (each frame once failed on
    // them, and the run ended "not usable" without naming the setting).
    let estimator = tmp.0.join("estimator.json");
    std::fs::write(
        &estimator,
        r#"{"odometry": {"estimator": {"method": "pso", "ambiguity_ratio": 2.0}}}"#,
    )
    .expect("estimator");
    let out = swarmpose(
        &[
            "odometry",
            "--out",
            s(&tmp.0.join("est")),
            "--config",
            s(&estimator),
        ],
        None,
    );
    check_error(
        &out,
        &[
            "estimator.json: configuration: estimator.ambiguity_ratio is 2: it must be a number from 0 to 1",
        ],
    );
}
