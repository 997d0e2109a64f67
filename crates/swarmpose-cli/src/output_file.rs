//! Output files that are never left half-written: each is written under a temporary name
//! beside its final one (in a folder created if missing) and renamed when complete, so a
//! full disk, an error or a kill leaves no truncated file under the final name.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::CliError;

/// An error writing `path` (exit status 1), naming it once.
pub fn write_error(path: &Path, e: &dyn std::fmt::Display) -> CliError {
    CliError::failure(format!("{}: cannot write: {e}", path.display()))
}

/// Creates the folder that will hold `path` (and its parents) if missing.
///
/// # Errors
/// Exit status 1 naming the folder.
pub fn create_parent(path: &Path) -> Result<(), CliError> {
    match path.parent() {
        Some(dir) if !dir.as_os_str().is_empty() => {
            std::fs::create_dir_all(dir).map_err(|e| write_error(dir, &e))
        }
        _ => Ok(()),
    }
}

/// The temporary name of `path` while it is written: `.NAME.partial-PID.EXT` in the same
/// folder (same extension, for writers that choose the format by it).
fn temporary(path: &Path) -> PathBuf {
    let name = path
        .file_name()
        .map_or_else(|| "output".into(), |n| n.to_string_lossy().into_owned());
    let ext = path
        .extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default();
    path.with_file_name(format!(".{name}.partial-{}{ext}", std::process::id()))
}

/// Writes `path` through `write` (given the temporary path), then renames it into place.
///
/// # Errors
/// Exit status 1 naming `path`; the temporary file is removed.
pub fn write_with(
    path: &Path,
    write: impl FnOnce(&Path) -> Result<(), String>,
) -> Result<(), CliError> {
    create_parent(path)?;
    let tmp = temporary(path);
    let result = write(&tmp).and_then(|()| {
        // Data on disk before the name points at it.
        std::fs::File::open(&tmp)
            .and_then(|f| f.sync_all())
            .and_then(|()| std::fs::rename(&tmp, path))
            .map_err(|e| e.to_string())
    });
    if let Err(e) = result {
        let _ = std::fs::remove_file(&tmp);
        // Messages of writers may name the temporary file: name the final one instead.
        let e = e.replace(&format!("{}: ", tmp.display()), "");
        return Err(write_error(path, &e));
    }
    Ok(())
}

/// Writes `bytes` to `path` whole (see [`write_with`]).
///
/// # Errors
/// Exit status 1 naming `path`.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    write_with(path, |tmp| {
        std::fs::File::create(tmp)
            .and_then(|mut f| f.write_all(bytes).and_then(|()| f.flush()))
            .map_err(|e| e.to_string())
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_renamed_into_place_and_a_failure_leaves_nothing() {
        let dir = std::env::temp_dir().join(format!("swarmpose-outfile-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.join("a/b/c.csv");
        write_bytes(&path, b"x\n").expect("write");
        assert_eq!(std::fs::read(&path).expect("read"), b"x\n");
        let e = write_with(&dir.join("a/d.png"), |tmp| {
            std::fs::write(tmp, b"half").map_err(|e| e.to_string())?;
            Err("disk full".into())
        })
        .expect_err("fails");
        assert_eq!(e.code, 1);
        assert!(
            e.message.ends_with("a/d.png: cannot write: disk full"),
            "{e}"
        );
        let left: Vec<_> = std::fs::read_dir(dir.join("a"))
            .expect("list")
            .filter_map(|e| e.ok().map(|e| e.file_name()))
            .collect();
        assert_eq!(
            left.len(),
            1,
            "b/ only, no d.png nor its temporary: {left:?}"
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
