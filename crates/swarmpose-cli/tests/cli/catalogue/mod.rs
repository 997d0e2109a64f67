//! Helpers of the bad-input catalogue: sequences copied from the shared data (a few
//! frames) into temp dirs, then broken one way each.
#![allow(dead_code)] // each test crate uses its own subset

use std::path::{Path, PathBuf};
use std::process::Output;

pub use crate::common::s;

/// Checks the exit status and that standard error's first line starts with `start`;
/// returns standard error.
pub fn expect(out: &Output, code: i32, start: &str) -> String {
    let stderr = String::from_utf8_lossy(&out.stderr).into_owned();
    assert_eq!(out.status.code(), Some(code), "{stderr}");
    for bad in ["panicked", "internal error", "stack backtrace"] {
        assert!(!stderr.contains(bad), "{bad}: {stderr}");
    }
    let line = stderr
        .lines()
        .find(|l| l.starts_with("swarmpose: error: "))
        .unwrap_or_default();
    assert!(
        line.starts_with(start),
        "expected {start:?}, got {stderr:?}"
    );
    stderr
}

/// `correspondences` on frames 0 and 1 of `seq`, writing into `tmp`.
pub fn corr(tmp: &crate::common::TempDir, seq: &Path, extra: &[&str]) -> Output {
    crate::common::correspondences(seq, ("0", "1"), &tmp.0.join("c.csv"), extra)
}

pub use crate::common::assert_success as succeeded;

fn copy(from: &Path, to: &Path) {
    if let Some(d) = to.parent() {
        std::fs::create_dir_all(d).expect("mkdir");
    }
    std::fs::copy(from, to).expect("copy");
}

/// The first `n` frames of the shared KITTI sequence in `dir/name` (images, calib.txt
/// and the first `n` ground-truth poses), or `None` when the data is absent (skipped).
pub fn kitti(dir: &Path, name: &str, n: usize) -> Option<PathBuf> {
    let root = swarmpose_testdata::dataset_for_test("kitti_vo_seq2")?;
    let seq = dir.join(name);
    for side in ["image_0", "image_1"] {
        for i in 0..n {
            let f = format!("{side}/{i:06}.png");
            copy(&root.join(&f), &seq.join(&f));
        }
    }
    copy(&root.join("calib.txt"), &seq.join("calib.txt"));
    let poses = std::fs::read_to_string(root.join("poses.txt")).expect("poses");
    let first: Vec<&str> = poses.lines().take(n).collect();
    std::fs::write(seq.join("poses.txt"), first.join("\n") + "\n").expect("poses");
    Some(seq)
}

/// The first `n` frames of the shared EuRoC sequence in `dir/name` (both cameras' lists,
/// images and sensor.yaml; no ground truth), or `None` when the data is absent.
pub fn euroc(dir: &Path, name: &str, n: usize) -> Option<PathBuf> {
    let root = swarmpose_testdata::dataset_for_test("euroc_v1_01_easy_micro")?;
    let seq = dir.join(name);
    for cam in ["cam0", "cam1"] {
        let from = root.join("mav0").join(cam);
        let to = seq.join("mav0").join(cam);
        copy(&from.join("sensor.yaml"), &to.join("sensor.yaml"));
        let list = std::fs::read_to_string(from.join("data.csv")).expect("data.csv");
        let mut kept = Vec::new();
        for line in list.lines() {
            if line.starts_with('#') {
                kept.push(line.to_owned());
                continue;
            }
            if kept.len() > n {
                break;
            }
            let name = line.split(',').nth(1).expect("file name").trim();
            copy(&from.join("data").join(name), &to.join("data").join(name));
            kept.push(line.to_owned());
        }
        std::fs::write(to.join("data.csv"), kept.join("\n") + "\n").expect("data.csv");
    }
    Some(seq)
}

/// The first `n` frames of the shared Karlsruhe sequence in `dir/name`, or `None`.
pub fn karlsruhe(dir: &Path, name: &str, n: usize) -> Option<PathBuf> {
    let root = swarmpose_testdata::dataset_for_test("karlsruhe_2010_03_09_drive_0023")?;
    let seq = dir.join(name);
    let images = root.join("2010_03_09_drive_0023_Images");
    for i in 0..n {
        for side in ["I1", "I2"] {
            let f = format!("{side}_{i:06}.png");
            copy(&images.join(&f), &seq.join(&f));
        }
    }
    copy(&root.join("calib.txt"), &seq.join("calib.txt"));
    Some(seq)
}

/// Replaces the line of `path` starting with `key` by `line` (or appends it when
/// `append`).
pub fn edit_line(path: &Path, key: &str, line: &str, append: bool) {
    let text = std::fs::read_to_string(path).expect("read");
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    if append {
        lines.push(line.to_owned());
    } else {
        let at = lines.iter().position(|l| l.starts_with(key)).expect("key");
        lines[at] = line.to_owned();
    }
    std::fs::write(path, lines.join("\n") + "\n").expect("write");
}

/// The 1-based number of the line of `path` starting with `key`.
pub fn line_of(path: &Path, key: &str) -> usize {
    let text = std::fs::read_to_string(path).expect("read");
    text.lines().position(|l| l.starts_with(key)).expect("key") + 1
}
