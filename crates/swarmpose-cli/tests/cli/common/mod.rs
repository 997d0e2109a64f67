//! Helpers shared by the CLI's integration tests: temp dirs, running the binary,
//! writing correspondence CSVs and checking its one-line errors.
#![allow(dead_code)] // each test crate uses its own subset

use std::io::Write;
use std::path::Path;
use std::process::{Command, Output, Stdio};

use nalgebra::Point3;
use serde_json::Value;

/// The correspondence CSV header.
pub const HEADER: &str = "src_x,src_y,src_z,dst_x,dst_y,dst_z";

pub use swarmpose_testdata::TempDir;

/// The path as a `&str` (temp paths are UTF-8).
pub fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// Runs the binary with `args`, feeding `stdin` if given; backtraces are switched on so
/// that one would show if anything panicked.
pub fn swarmpose(args: &[&str], stdin: Option<&str>) -> Output {
    let mut child = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .args(args)
        .env("RUST_BACKTRACE", "1")
        .stdin(if stdin.is_some() {
            Stdio::piped()
        } else {
            Stdio::null()
        })
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run swarmpose");
    if let Some(text) = stdin {
        let mut pipe = child.stdin.take().expect("stdin pipe");
        pipe.write_all(text.as_bytes()).expect("write stdin");
    }
    child.wait_with_output().expect("wait for swarmpose")
}

/// The directory of the shared data set `name`, or `None` (printed as skipped) when it
/// is absent; under `CI=true` an absent data set fails the test.
pub fn shared_dataset(name: &str) -> Option<std::path::PathBuf> {
    let dir = swarmpose_testdata::data_root().join(name);
    if dir.is_dir() {
        return Some(dir);
    }
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true: {} not found",
        dir.display()
    );
    eprintln!("SKIPPED: {} not found", dir.display());
    None
}

/// Asserts that a run exited with status 0, showing its standard error otherwise.
pub fn assert_success(out: &Output) {
    assert_eq!(
        out.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
}

/// Runs `swarmpose odometry [SEQUENCE] --out OUT_DIR --quiet EXTRA...` (the built-in
/// synthetic sequence without a `sequence`).
pub fn odometry(sequence: Option<&Path>, out_dir: &Path, extra: &[&str]) -> Output {
    let mut args = vec!["odometry"];
    args.extend(sequence.map(s));
    args.extend(["--out", s(out_dir), "--quiet"]);
    args.extend_from_slice(extra);
    swarmpose(&args, None)
}

/// Runs `swarmpose correspondences SEQUENCE --frames A B --out OUT EXTRA...`.
pub fn correspondences(
    sequence: &Path,
    (a, b): (&str, &str),
    out: &Path,
    extra: &[&str],
) -> Output {
    let mut args = vec![
        "correspondences",
        s(sequence),
        "--frames",
        a,
        b,
        "--out",
        s(out),
    ];
    args.extend_from_slice(extra);
    swarmpose(&args, None)
}

/// `swarmpose evaluate ESTIMATE TRUTH --json` of two files of `dir`, its JSON.
pub fn evaluate_json(dir: &Path, estimate: &str, truth: &str) -> Value {
    let (estimate, truth) = (dir.join(estimate), dir.join(truth));
    json_of(&swarmpose(
        &["evaluate", s(&estimate), s(&truth), "--json"],
        None,
    ))
}

/// A correspondence CSV; values written in Rust's shortest round-trip form.
pub fn csv(src: &[Point3<f64>], dst: &[Point3<f64>]) -> String {
    let mut text = format!("{HEADER}\n");
    for (s, d) in src.iter().zip(dst) {
        text.push_str(&format!(
            "{},{},{},{},{},{}\n",
            s.x, s.y, s.z, d.x, d.y, d.z
        ));
    }
    text
}

/// Parses the one JSON line on stdout of a successful run.
pub fn json_of(out: &Output) -> Value {
    assert_eq!(
        out.status.code(),
        Some(0),
        "stderr: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    assert!(
        out.stderr.is_empty(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout.clone()).expect("utf-8 stdout");
    assert_eq!(text.lines().count(), 1, "one line of JSON: {text}");
    serde_json::from_str(&text).expect("stdout is JSON")
}

/// Checks a failed run: status 2, nothing on stdout, exactly one non-empty line on
/// stderr that contains every `needle`, and no sign of a panic.
pub fn check_error(out: &Output, needles: &[&str]) -> String {
    let stderr = String::from_utf8(out.stderr.clone()).expect("utf-8 stderr");
    assert_eq!(out.status.code(), Some(2), "stderr: {stderr}");
    assert!(out.stdout.is_empty(), "stdout should be empty");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "exactly one line: {stderr:?}");
    let line = lines[0];
    assert!(line.starts_with("swarmpose: error: "), "{line}");
    assert!(line.len() > "swarmpose: error: ".len(), "{line}");
    for bad in [
        "panicked",
        "RUST_BACKTRACE",
        "internal error",
        "stack backtrace",
    ] {
        assert!(!stderr.contains(bad), "{bad}: {stderr}");
    }
    for needle in needles {
        assert!(line.contains(needle), "{needle:?} not in {line:?}");
    }
    line.to_owned()
}
