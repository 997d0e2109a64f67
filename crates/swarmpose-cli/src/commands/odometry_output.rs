//! The output folder of a run: created and checked writable before any work, files
//! streamed line by line (each line flushed, so a run stopped at any point leaves whole
//! lines) or written whole under a temporary name and renamed when complete, and a
//! manifest of what the run wrote, so that files an earlier run left there are removed.

use std::fs::{File, OpenOptions};
use std::io::Write;
use std::path::{Path, PathBuf};

use crate::error::CliError;

/// Name of the manifest in an output folder.
pub const MANIFEST: &str = ".swarmpose-manifest";

use crate::output_file::write_error;

/// An output folder being written by one run.
#[derive(Debug)]
pub struct OutputDir {
    path: PathBuf,
}

impl OutputDir {
    /// Creates `path` (and its parents) if needed, checks that files can be written in
    /// it, and removes the files an earlier run's manifest lists.
    ///
    /// # Errors
    /// Exit status 1, naming the folder, when it cannot be created or written.
    pub fn prepare(path: &Path) -> Result<Self, CliError> {
        std::fs::create_dir_all(path).map_err(|e| write_error(path, &e))?;
        let probe = path.join(".swarmpose-write-check");
        std::fs::write(&probe, b"").map_err(|e| write_error(path, &e))?;
        let _ = std::fs::remove_file(&probe);
        let manifest = path.join(MANIFEST);
        if let Ok(text) = std::fs::read_to_string(&manifest) {
            for name in text.lines().map(str::trim).filter(|n| !n.is_empty()) {
                // Only plain names inside the folder.
                if !name.contains('/') && !name.contains('\\') && name != ".." {
                    let _ = std::fs::remove_file(path.join(name));
                }
            }
        }
        std::fs::write(&manifest, b"").map_err(|e| write_error(&manifest, &e))?;
        Ok(Self {
            path: path.to_owned(),
        })
    }

    /// The folder.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn record(&self, name: &str) -> Result<(), CliError> {
        let manifest = self.path.join(MANIFEST);
        let mut f = OpenOptions::new()
            .append(true)
            .create(true)
            .open(&manifest)
            .map_err(|e| write_error(&manifest, &e))?;
        writeln!(f, "{name}").map_err(|e| write_error(&manifest, &e))
    }

    /// Creates `name` (listed in the manifest) for a writer that streams into it.
    ///
    /// # Errors
    /// Exit status 1 naming the file.
    pub fn create(&self, name: &str) -> Result<(File, PathBuf), CliError> {
        self.record(name)?;
        let path = self.path.join(name);
        let file = File::create(&path).map_err(|e| write_error(&path, &e))?;
        Ok((file, path))
    }

    /// Writes `name` whole: to a temporary name first, renamed when complete, so that no
    /// file under its final name is ever truncated.
    ///
    /// # Errors
    /// Exit status 1 naming the file.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<(), CliError> {
        self.record(name)?;
        crate::output_file::write_bytes(&self.path.join(name), bytes)
    }
}

/// A file written line by line, each line flushed at once; a line that cannot be written
/// whole (a full disk) is cut off, so the file holds whole lines only.
#[derive(Debug)]
pub struct StreamFile {
    path: PathBuf,
    file: File,
    /// Bytes of the whole lines written so far.
    len: u64,
}

impl StreamFile {
    /// Creates `name` in `dir`, with a first line `header` if given.
    ///
    /// # Errors
    /// Exit status 1 naming the file.
    pub fn create(dir: &OutputDir, name: &str, header: Option<&str>) -> Result<Self, CliError> {
        let (file, path) = dir.create(name)?;
        let mut s = Self { path, file, len: 0 };
        if let Some(h) = header {
            s.line(h)?;
        }
        Ok(s)
    }

    /// Appends one line (a line end is added) and flushes it.
    ///
    /// # Errors
    /// Exit status 1 naming the file.
    pub fn line(&mut self, text: &str) -> Result<(), CliError> {
        let mut buf = String::with_capacity(text.len() + 1);
        buf.push_str(text);
        buf.push('\n');
        match self
            .file
            .write_all(buf.as_bytes())
            .and_then(|()| self.file.flush())
        {
            Ok(()) => {
                self.len += buf.len() as u64;
                Ok(())
            }
            Err(e) => {
                // A full disk may have taken part of the line: cut the file back to its
                // whole lines.
                let _ = self.file.set_len(self.len);
                Err(write_error(&self.path, &e))
            }
        }
    }
}
