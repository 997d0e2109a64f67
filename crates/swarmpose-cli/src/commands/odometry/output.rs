//! The output folder of a run ([`swarmpose_runs::output_dir`]: one run at a time, a
//! manifest, files streamed line by line), shared with the ROS 2 node.

pub use swarmpose_runs::output_dir::{OutputDir, StreamFile};

use crate::error::CliError;
use crate::streams::warn;

/// Prepares the output folder `path` ([`OutputDir::prepare`]) and warns of what that did.
///
/// # Errors
/// Exit status 1, naming the folder, when it cannot be created or written, or when
/// another run holds it.
pub fn prepare(path: &std::path::Path) -> Result<OutputDir, CliError> {
    let dir = OutputDir::prepare(path)?;
    for note in dir.notes() {
        warn(note);
    }
    Ok(dir)
}
