//! Shared by the tests: the Python with `rosbags` that makes and reads bags independently
//! of this crate, and the MCAP writer (swarmpose-testdata's).

#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

/// The Python interpreter with `rosbags` (`$SWARMPOSE_PYTHON`, else `python3`), or `None`
/// after printing why the test is skipped (a failure under `CI=true`, where .ci/run
/// installs it).
pub fn python_with_rosbags() -> Option<String> {
    let py = std::env::var("SWARMPOSE_PYTHON").unwrap_or_else(|_| "python3".to_owned());
    let ok = Command::new(&py)
        .args(["-c", "import rosbags, numpy"])
        .output()
        .is_ok_and(|o| o.status.success());
    if ok {
        return Some(py);
    }
    let msg = format!(
        "{py} cannot import rosbags and numpy (pip install rosbags; or set SWARMPOSE_PYTHON)"
    );
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true: {msg}"
    );
    eprintln!("SKIPPED: {msg}");
    None
}

/// The test scripts' folder.
pub fn scripts() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/py")
}

/// Runs `script` of [`scripts`] with `args`; panics with its output when it fails.
pub fn run_script(py: &str, script: &str, args: &[&Path]) {
    let out = Command::new(py)
        .arg(scripts().join(script))
        .args(args)
        .output()
        .expect("run python");
    assert!(
        out.status.success(),
        "{script} failed: {}{}",
        String::from_utf8_lossy(&out.stdout),
        String::from_utf8_lossy(&out.stderr)
    );
}

/// A fresh scratch folder under the target directory.
pub fn scratch(name: &str) -> PathBuf {
    let dir = Path::new(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).expect("scratch dir");
    dir
}

#[allow(unused_imports)] // each test file uses its own subset
pub use swarmpose_testdata::bags::{TopicData, write_mcap};
