//! Reading the inputs named on the command line: a path, or `-` for standard input.

use std::path::Path;

use swarmpose_core::Correspondences;
use swarmpose_data::{STDIN_NAME, correspondence_csv};

use crate::error::CliError;

/// True when `path` is `-`, the conventional name of standard input.
pub fn is_stdin(path: &Path) -> bool {
    path.as_os_str() == "-"
}

/// How messages and outputs name `path`: itself, or `<stdin>` for `-`.
pub fn display_name(path: &Path) -> String {
    if is_stdin(path) {
        STDIN_NAME.to_owned()
    } else {
        path.display().to_string()
    }
}

/// Reads a correspondence CSV from `path`, or from standard input for `-`.
///
/// # Errors
/// A usage error naming the input, the line and the problem.
pub fn read_correspondences(path: &Path) -> Result<Correspondences, CliError> {
    let data = if is_stdin(path) {
        correspondence_csv::read_from(std::io::stdin().lock(), STDIN_NAME)?
    } else {
        correspondence_csv::read_path(path)?
    };
    Ok(data)
}
