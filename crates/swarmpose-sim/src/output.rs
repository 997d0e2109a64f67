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

/// Writes `contents` to `path` whole: under a temporary name beside it first, renamed
/// when complete, so that an error, a full disk or a kill never leaves a truncated file
/// under the final name.
///
/// # Errors
/// [`SimError::Io`] naming the file (the temporary file is removed).
pub fn write_file(path: &Path, contents: impl AsRef<[u8]>) -> Result<(), SimError> {
    use std::io::Write;
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let tmp = path.with_file_name(format!(".{name}.partial-{}", std::process::id()));
    let result = fs::File::create(&tmp)
        .and_then(|mut f| f.write_all(contents.as_ref()).and_then(|()| f.sync_all()))
        .and_then(|()| fs::rename(&tmp, path));
    result.map_err(|e| {
        let _ = fs::remove_file(&tmp);
        SimError::io(path, e)
    })
}
