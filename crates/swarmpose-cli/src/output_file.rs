//! Output files that harm nothing ([`swarmpose_data::output`]): each is written whole
//! under a temporary name beside its final one (in a folder created if missing) and
//! renamed when complete, so a full disk, an error or a kill leaves no truncated file
//! under the final name; a FIFO or a character device (`--out /dev/stdout`) is written
//! through and never replaced; a folder or a block device is refused.

use std::path::Path;

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

/// Checks before any work that `path` can be an output: not a folder, a block device or
/// a socket (nor a link to one).
///
/// # Errors
/// Exit status 1 naming `path` and what it is.
pub fn check_target(path: &Path) -> Result<(), CliError> {
    swarmpose_data::output::target(path)
        .map(drop)
        .map_err(|e| write_error(path, &e))
}

/// Writes `bytes` to `path` whole (see the module documentation).
///
/// # Errors
/// Exit status 1 naming `path`; no temporary file is left.
pub fn write_bytes(path: &Path, bytes: &[u8]) -> Result<(), CliError> {
    create_parent(path)?;
    swarmpose_data::output::write_file(path, bytes).map_err(|e| write_error(path, &e))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_file_is_renamed_into_place_in_a_new_folder_and_a_folder_is_refused() {
        let dir = std::env::temp_dir().join(format!("swarmpose-outfile-{}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        let path = dir.join("a/b/c.csv");
        write_bytes(&path, b"x\n").expect("write");
        assert_eq!(std::fs::read(&path).expect("read"), b"x\n");
        let e = write_bytes(&dir.join("a/b"), b"x\n").expect_err("a folder");
        assert_eq!(e.code, 1);
        assert!(
            e.message
                .ends_with("a/b: cannot write: a folder, not a file: refused (nothing written)"),
            "{e}"
        );
        assert!(check_target(&dir.join("a")).is_err());
        assert!(check_target(&dir.join("a/new.csv")).is_ok());
        let left: Vec<_> = std::fs::read_dir(dir.join("a/b"))
            .expect("list")
            .filter_map(|e| e.ok().map(|e| e.file_name()))
            .collect();
        assert_eq!(left.len(), 1, "c.csv only: {left:?}");
        let _ = std::fs::remove_dir_all(&dir);
    }
}
