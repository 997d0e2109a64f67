//! Output folders: created and checked writable before any work starts.

use std::fs;
use std::path::Path;

use crate::error::SimError;

/// Creates `dir` (and parents) and checks a file can be written in it.
///
/// # Errors
/// [`SimError::Io`] naming the folder when it cannot be created or written to (for
/// example a path under a regular file, or a read-only place).
pub fn ensure_writable_dir(dir: &Path) -> Result<(), SimError> {
    if dir.exists() && !dir.is_dir() {
        return Err(SimError::io(
            dir,
            std::io::Error::new(std::io::ErrorKind::AlreadyExists, "not a folder"),
        ));
    }
    fs::create_dir_all(dir).map_err(|e| SimError::io(dir, e))?;
    let probe = dir.join(format!(".swarmpose-write-test-{}", std::process::id()));
    fs::write(&probe, b"ok").map_err(|e| SimError::io(dir, e))?;
    fs::remove_file(&probe).map_err(|e| SimError::io(&probe, e))?;
    Ok(())
}

/// Writes `contents` to `path` whole ([`swarmpose_data::output::write_file`]: under a
/// temporary name beside it first, renamed when complete, so that an error, a full disk
/// or a kill never leaves a truncated file under the final name; a FIFO or a character
/// device is written through, never replaced; a folder or a block device is refused).
///
/// # Errors
/// [`SimError::Io`] naming the file (the temporary file is removed).
pub fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), SimError> {
    swarmpose_data::output::write_file(path, contents.as_ref()).map_err(|e| SimError::io(path, e))
}
