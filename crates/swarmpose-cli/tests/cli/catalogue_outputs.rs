//! The bad-input and fault catalogue of outputs and streams (issue 16): exit status and
//! first words of the message for non-finite metrics, reflections, closed and full
//! standard streams, unwritable or reused output folders, runs in which nothing is
//! tracked, and options that would make every motion the identity.

use std::process::{Command, Stdio};

use crate::catalogue::{expect, kitti, s};
use crate::common::{TempDir, assert_success, odometry, swarmpose};

/// KITTI poses moving along z, `n` lines; `last` replaces the last line when given.
fn poses(n: usize, last: Option<&str>) -> String {
    let mut lines: Vec<String> = (0..n)
        .map(|i| format!("1 0 0 0 0 1 0 0 0 0 1 {}", 0.8 * i as f64))
        .collect();
    if let Some(l) = last {
        lines[n - 1] = l.to_owned();
    }
    lines.join("\n") + "\n"
}

#[test]
fn evaluate_refuses_reflections_and_flags_non_finite_metrics() {
    let tmp = TempDir::new("cat-eval");
    let est = tmp.file("est.txt", &poses(6, None));
    let huge = tmp.file(
        "huge.txt",
        &poses(6, Some("1 0 0 1e308 0 1 0 0 0 0 1 1e308")),
    );
    let out = swarmpose(&["evaluate", s(&est), s(&huge)], None);
    expect(&out, 3, "swarmpose: error: not usable: ");
    assert!(!out.stdout.is_empty(), "the table is still printed");
    let out = swarmpose(&["evaluate", s(&est), s(&huge), "--json"], None);
    expect(&out, 3, "swarmpose: error: not usable: ");
    let mirror = tmp.file("mirror.txt", &poses(6, Some("-1 0 0 0 0 1 0 0 0 0 1 4")));
    let out = swarmpose(&["evaluate", s(&est), s(&mirror)], None);
    expect(
        &out,
        2,
        &format!(
            "swarmpose: error: {}:6: the 3x3 part has determinant -1.000 (a reflection)",
            s(&mirror)
        ),
    );
    let skew = tmp.file("skew.txt", &poses(6, Some("1 0.5 0 0 0 1 0 0 0 0 1 4")));
    let out = swarmpose(&["evaluate", s(&est), s(&skew)], None);
    expect(
        &out,
        2,
        &format!(
            "swarmpose: error: {}:6: the 3x3 part is not a rotation",
            s(&skew)
        ),
    );
}

/// Runs `args` with standard output a pipe whose reader is closed before the start: a
/// quiet end (141), never a panic.
fn closed_stdout(args: &[&str]) {
    let (reader, writer) = std::io::pipe().expect("pipe");
    drop(reader);
    let out = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .stdout(writer)
        .stderr(Stdio::piped())
        .output()
        .expect("run");
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(141), "{args:?}: {stderr}");
    assert!(stderr.is_empty(), "{args:?}: {stderr}");
}

/// Runs `args` with standard output (or error) on /dev/full.
fn full(args: &[&str], stderr_full: bool) -> std::process::Output {
    let dev = || {
        std::fs::OpenOptions::new()
            .write(true)
            .open("/dev/full")
            .expect("/dev/full")
    };
    let mut cmd = Command::new(env!("CARGO_BIN_EXE_swarmpose"));
    cmd.args(args);
    if stderr_full {
        cmd.stderr(dev()).stdout(Stdio::piped());
    } else {
        cmd.stdout(dev()).stderr(Stdio::piped());
    }
    cmd.output().expect("run")
}

#[test]
fn closed_and_full_standard_streams_never_panic() {
    let tmp = TempDir::new("cat-streams");
    let est = tmp.file("est.txt", &poses(6, None));
    let bad = tmp.file("bad.txt", "1 2 3\n");
    let csv = tmp.file(
        "c.csv",
        "src_x,src_y,src_z,dst_x,dst_y,dst_z\n0,0,1,0,0,1\n1,0,2,1,0,2\n0,1,3,0,1,3\n2,2,5,2,2,5\n1,3,4,1,3,4\n",
    );
    let eval = ["evaluate", s(&est), s(&est)];
    let register = ["register", s(&csv), "--method", "svd"];
    for args in [&eval[..], &register[..], &["--help"][..]] {
        closed_stdout(args);
    }
    if !std::path::Path::new("/dev/full").exists() {
        eprintln!("SKIPPED: /dev/full cases (no /dev/full)");
        return;
    }
    for args in [&eval[..], &register[..]] {
        let out = full(args, false);
        expect(&out, 1, "swarmpose: error: cannot write to standard output");
    }
    // An error with standard error full: the status still says it, no abort.
    let out = full(&["evaluate", s(&est), s(&bad)], true);
    assert_eq!(out.status.code(), Some(2));
    let out = full(&eval, true);
    assert_eq!(out.status.code(), Some(0));
}

#[test]
fn odometry_checks_its_output_folder_first_and_never_mixes_runs() {
    let tmp = TempDir::new("cat-out");
    let Some(seq) = kitti(&tmp.0, "k", 3) else {
        return;
    };
    // An --out that cannot be a folder: refused before the first frame.
    let file = tmp.file("plain-file", "x");
    let out_dir = file.join("out");
    let out = odometry(Some(&seq), &out_dir, &[]);
    expect(
        &out,
        1,
        &format!("swarmpose: error: {}: cannot write", s(&out_dir)),
    );
    assert!(out.stdout.is_empty(), "no frame was run");
    // A reused --out: files of the earlier run that this one does not write are removed.
    let out_dir = tmp.0.join("o");
    let out = odometry(Some(&seq), &out_dir, &[]);
    assert_success(&out);
    for f in ["groundtruth.kitti.txt", "evaluation.json", "errors.png"] {
        assert!(out_dir.join(f).is_file(), "{f} written with ground truth");
    }
    std::fs::remove_file(seq.join("poses.txt")).expect("rm");
    let out = odometry(Some(&seq), &out_dir, &[]);
    assert_eq!(out.status.code(), Some(0));
    for f in [
        "groundtruth.kitti.txt",
        "groundtruth.tum.txt",
        "evaluation.json",
        "errors.png",
    ] {
        assert!(!out_dir.join(f).exists(), "{f} of the earlier run removed");
    }
    let manifest = std::fs::read_to_string(out_dir.join(".swarmpose-manifest")).expect("manifest");
    assert!(manifest.contains("trajectory.kitti.txt") && !manifest.contains("evaluation.json"));
    let left: Vec<String> = std::fs::read_dir(&out_dir)
        .expect("list")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.contains("partial") || n.contains("write-check"))
        .collect();
    assert!(left.is_empty(), "no temporary file left: {left:?}");
}

#[test]
fn runs_that_track_nothing_are_not_usable() {
    let tmp = TempDir::new("cat-usable");
    let Some(seq) = kitti(&tmp.0, "k", 3) else {
        return;
    };
    let out_dir = tmp.0.join("o");
    let out = odometry(Some(&seq), &out_dir, &["--min-inliers", "100000"]);
    expect(
        &out,
        3,
        "swarmpose: error: not usable: 0 motions of 2 were tracked",
    );
    let stdout = String::from_utf8_lossy(&out.stdout);
    let last = stdout.lines().last().unwrap_or_default();
    assert!(
        last.ends_with(
            "(3 frames: 0 of 2 motions tracked, 0 at constant velocity, 3 lost, 0 keyframes)"
        ),
        "{stdout}"
    );
    let traj = std::fs::read_to_string(out_dir.join("trajectory.kitti.txt")).expect("trajectory");
    assert_eq!(traj.lines().count(), 3);
    assert!(
        traj.lines()
            .all(|l| l.split_whitespace().count() == 12 && !l.is_empty())
    );
    // A disparity offset of 1e9 px put every point at the camera and every motion at the
    // identity, with exit 0: now refused as an option.
    for flag in ["--disparity-offset", "--disparity-quadratic"] {
        let out = odometry(Some(&seq), &out_dir, &[flag, "1e9"]);
        expect(
            &out,
            2,
            &format!("swarmpose: error: {flag} 1e9 px is outside -100..100 px"),
        );
    }
}
