//! # swarmpose-testdata
//!
//! Where the tests and benchmarks of the workspace find the shared data sets (KITTI,
//! Karlsruhe, EuRoC clips and recorded bags; their licences keep them out of the
//! repository), and the project's rule for a test whose data set is absent: skipped with
//! a printed reason, except under `CI=true`, where it fails; and the tests' temporary
//! folders ([`TempDir`]). With the feature `ros`, the ROS 2 bags the tests write: MCAP
//! files (module `bags`) and RGB-D input, a bag and the TUM folder of the same frames
//! (module `rgbd`). A dev-dependency only: no library of the workspace depends on it.
#![deny(missing_docs)]
#![forbid(unsafe_code)]

#[cfg(feature = "ros")]
pub mod bags;
#[cfg(feature = "ros")]
pub mod rgbd;

use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The shared data set `name` for a test, or `None` after printing why it is skipped.
///
/// The project's policy for data-dependent tests: a missing data set is skipped with a
/// printed reason, except under `CI=true`, where it is a failure.
///
/// # Panics
/// Under `CI=true` when the data set is absent.
#[must_use]
pub fn dataset_for_test(name: &str) -> Option<PathBuf> {
    let dir = data_root().join(name);
    if dir.is_dir() {
        return Some(dir);
    }
    let msg = format!(
        "data set {} not found (set SWARMPOSE_DATA to the data root)",
        dir.display()
    );
    assert!(
        std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true: {msg}"
    );
    eprintln!("SKIPPED: {msg}");
    None
}

/// The data root: `$SWARMPOSE_DATA`, or `../shared/data` next to the repository.
#[must_use]
pub fn data_root() -> PathBuf {
    match std::env::var_os("SWARMPOSE_DATA") {
        Some(p) if !p.is_empty() => PathBuf::from(p),
        _ => Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
    }
}

/// A fresh, empty folder under the system's temporary folder, removed with what it holds
/// on drop (for tests).
#[derive(Debug)]
pub struct TempDir(pub PathBuf);

impl TempDir {
    /// A new folder whose name holds `tag`, the process id, a counter and the clock's
    /// nanoseconds, so that tests running at the same time never share one.
    ///
    /// # Panics
    /// When the folder cannot be created (meant for tests only).
    #[must_use]
    pub fn new(tag: &str) -> Self {
        static COUNTER: AtomicUsize = AtomicUsize::new(0);
        let n = COUNTER.fetch_add(1, Ordering::Relaxed);
        let nanos = std::time::SystemTime::now()
            .duration_since(std::time::UNIX_EPOCH)
            .map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!(
            "swarmpose-test-{tag}-{}-{n}-{nanos}",
            std::process::id()
        ));
        std::fs::create_dir_all(&dir).expect("create temp dir");
        Self(dir)
    }

    /// The path of `name` in the folder.
    #[must_use]
    pub fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    /// Writes `text` to `name` in the folder; returns its path.
    ///
    /// # Panics
    /// When the file cannot be written (meant for tests only).
    pub fn file(&self, name: &str, text: &str) -> PathBuf {
        let path = self.0.join(name);
        std::fs::write(&path, text).expect("write test file");
        path
    }
}

impl Drop for TempDir {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.0);
    }
}
