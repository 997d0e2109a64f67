//! Shared helpers of the dataset tests.

use std::path::PathBuf;

/// The directory of a shared data set, or `None` (with the reason printed) when it is
/// absent. Under `CI=true` absence is a failure.
pub fn dataset(name: &str) -> Option<PathBuf> {
    let dir = swarmpose_datasets::data_root().join(name);
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
