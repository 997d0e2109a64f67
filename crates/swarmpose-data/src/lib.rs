//! # swarmpose-data
//!
//! The file formats of swarmpose, kept out of the I/O-free core:
//!
//! - [`correspondence_csv`]: matched 3D points, one correspondence per row,
//!   `src_x,src_y,src_z,dst_x,dst_y,dst_z` in metres, with `dst = R src + t`;
//! - [`register_report`]: the JSON report of `swarmpose register`, read back to draw
//!   its inliers;
//! - [`truth`]: the ground-truth JSON written beside each scenario CSV by the scenario
//!   generator (`gen_scenarios.py`);
//! - [`output`]: how every output file is written (whole, and never over a device, a
//!   FIFO or a folder).
//!
//! Every error names its input (a file path, or `<stdin>`) and, where one applies, the
//! 1-based line number, so a command-line tool can print it as one line.
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod correspondence_csv;
pub mod output;
pub mod register_report;
pub mod truth;

pub use correspondence_csv::{CsvError, CsvErrorKind, HEADER, HEADER_WITH_COVARIANCE, STDIN_NAME};
pub use truth::{InvalidTruth, ScenarioTruth, TruthError, TruthErrorKind};

#[cfg(test)]
pub(crate) mod test_util {
    use std::path::PathBuf;
    use std::sync::atomic::{AtomicUsize, Ordering};

    /// A fresh, empty directory under the system temp dir, removed on drop.
    pub struct TempDir(pub PathBuf);

    impl TempDir {
        pub fn new(tag: &str) -> Self {
            static COUNTER: AtomicUsize = AtomicUsize::new(0);
            let n = COUNTER.fetch_add(1, Ordering::Relaxed);
            let nanos = std::time::SystemTime::now()
                .duration_since(std::time::UNIX_EPOCH)
                .map_or(0, |d| d.subsec_nanos());
            let dir = std::env::temp_dir().join(format!(
                "swarmpose-data-{tag}-{}-{n}-{nanos}",
                std::process::id()
            ));
            std::fs::create_dir_all(&dir).expect("create temp dir");
            Self(dir)
        }

        pub fn path(&self, name: &str) -> PathBuf {
            self.0.join(name)
        }
    }

    impl Drop for TempDir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }
}
