//! The output folder of a run: one run at a time (a lock held while it writes),
//! created and checked writable before any work, files streamed line by line (each
//! line flushed, so a run stopped at any point leaves whole lines) or written whole
//! under a temporary name and renamed when complete, and a manifest of what the run
//! wrote, so that files an earlier run left there are removed.

use std::fs::{File, OpenOptions, TryLockError};
use std::io::{Read, Seek, Write};
use std::path::{Path, PathBuf};

use swarmpose_odometry::FrameResult;

use crate::error::RunError;
use crate::output::{
    COVARIANCE_HEADER, FRAMES_HEADER, covariance_row, csv_record, frames_row, kitti_line, tum_line,
};

/// An error writing `path`, naming it once.
fn write_error(path: &Path, e: &dyn std::fmt::Display) -> RunError {
    RunError::Write {
        path: path.to_owned(),
        message: e.to_string(),
    }
}

/// Name of the manifest in an output folder.
pub const MANIFEST: &str = ".swarmpose-manifest";

/// Name of the lock file of an output folder: locked (an advisory lock of the whole
/// file) by the run writing the folder, and released when that run ends however it
/// ends, a SIGKILL included. It holds the process id of the run.
pub const LOCK: &str = ".swarmpose-lock";

/// Every file a run may write in its folder: what [`OutputDir::prepare`] removes from a
/// folder an earlier version wrote without a manifest, and the only names a run records.
pub const OUTPUT_NAMES: [&str; 16] = [
    crate::config::FILE_NAME,
    "trajectory.kitti.txt",
    "trajectory.tum.txt",
    "frames.csv",
    "motion_covariance.csv",
    "split_check.csv",
    "odometry.mcap",
    "calibration.json",
    "trajectory.smoothed.kitti.txt",
    "trajectory.smoothed.tum.txt",
    "groundtruth.kitti.txt",
    "groundtruth.tum.txt",
    "evaluation.json",
    "trajectory.png",
    "trajectory.svg",
    "errors.png",
];

/// An output folder being written by one run (the folder stays locked while this lives).
#[derive(Debug)]
pub struct OutputDir {
    path: PathBuf,
    /// The locked [`LOCK`] file.
    _lock: File,
    /// What preparing it did that a user should hear of.
    notes: Vec<String>,
}

/// Locks `dir`'s [`LOCK`] file and writes this process's id in it.
fn lock(dir: &Path) -> Result<File, RunError> {
    let path = dir.join(LOCK);
    let mut file = OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(|e| write_error(dir, &e))?;
    match file.try_lock() {
        Ok(()) => {}
        Err(TryLockError::WouldBlock) => {
            let mut holder = String::new();
            let _ = file.read_to_string(&mut holder);
            let holder = holder.trim();
            let by = if holder.is_empty() {
                String::new()
            } else {
                format!(" (process {holder})")
            };
            return Err(write_error(
                dir,
                &format!(
                    "in use by another run{by}: one run at a time per output folder (give \
                     another --out)"
                ),
            ));
        }
        Err(TryLockError::Error(e)) => return Err(write_error(&path, &e)),
    }
    file.set_len(0)
        .and_then(|()| file.rewind())
        .and_then(|()| write!(file, "{}", std::process::id()))
        .map_err(|e| write_error(&path, &e))?;
    Ok(file)
}

/// Removes `dir/name` when it is a regular file (a FIFO, a device or a link put in its
/// place stays); returns whether it did.
fn remove_regular(dir: &Path, name: &str) -> bool {
    let path = dir.join(name);
    let plain = !name.contains('/') && !name.contains('\\') && name != "..";
    plain
        && std::fs::symlink_metadata(&path).is_ok_and(|m| m.is_file())
        && std::fs::remove_file(path).is_ok()
}

/// Removes what an earlier run left in `dir`: the temporaries of a run that was killed
/// (none can be another's: the folder is locked), and the files of the earlier run's
/// manifest, or, in a folder an earlier version wrote without one, the files a run
/// writes ([`OUTPUT_NAMES`], with a warning naming them).
fn clean(dir: &Path) -> Result<Vec<String>, RunError> {
    let entries = std::fs::read_dir(dir).map_err(|e| write_error(dir, &e))?;
    let names: Vec<String> = entries
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .collect();
    for name in &names {
        if swarmpose_data::output::temporary_of(name).is_some() {
            remove_regular(dir, name);
        }
    }
    match std::fs::read_to_string(dir.join(MANIFEST)) {
        Ok(text) => {
            for name in text.lines().map(str::trim).filter(|n| !n.is_empty()) {
                remove_regular(dir, name);
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            let removed: Vec<&str> = OUTPUT_NAMES
                .into_iter()
                .filter(|n| names.iter().any(|m| m == n) && remove_regular(dir, n))
                .collect();
            if !removed.is_empty() {
                return Ok(vec![format!(
                    "{}: no {MANIFEST} (a folder of an earlier version): \
                     removed its {} before this run writes its own",
                    dir.display(),
                    removed.join(", ")
                )]);
            }
        }
        Err(e) => return Err(write_error(&dir.join(MANIFEST), &e)),
    }
    Ok(Vec::new())
}

impl OutputDir {
    /// Creates `path` (and its parents) if needed, locks it for this run, checks that
    /// files can be written in it, and removes what an earlier run left there (see
    /// `clean` in this file).
    ///
    /// # Errors
    /// An error naming the folder, when it cannot be created or written, or when
    /// another run holds it.
    pub fn prepare(path: &Path) -> Result<Self, RunError> {
        std::fs::create_dir_all(path).map_err(|e| write_error(path, &e))?;
        let lock = lock(path)?;
        let probe = path.join(".swarmpose-write-check");
        std::fs::write(&probe, b"").map_err(|e| write_error(path, &e))?;
        let _ = std::fs::remove_file(&probe);
        let notes = clean(path)?;
        let manifest = path.join(MANIFEST);
        std::fs::write(&manifest, b"").map_err(|e| write_error(&manifest, &e))?;
        Ok(Self {
            path: path.to_owned(),
            _lock: lock,
            notes,
        })
    }

    /// What preparing the folder did that a user should hear of (files of an earlier
    /// version removed), one line each.
    #[must_use]
    pub fn notes(&self) -> &[String] {
        &self.notes
    }

    /// The folder.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn record(&self, name: &str) -> Result<(), RunError> {
        if !OUTPUT_NAMES.contains(&name) {
            // A file not in the list would escape the cleaning of older folders.
            return Err(write_error(
                &self.path.join(name),
                &"internal error (a bug): not among the output names",
            ));
        }
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
    /// An error naming the file.
    pub fn create(&self, name: &str) -> Result<(File, PathBuf), RunError> {
        self.record(name)?;
        let path = self.path.join(name);
        let file =
            swarmpose_data::output::create_stream(&path).map_err(|e| write_error(&path, &e))?;
        Ok((file, path))
    }

    /// Writes `name` whole: to a temporary name first, renamed when complete, so that no
    /// file under its final name is ever truncated.
    ///
    /// # Errors
    /// An error naming the file.
    pub fn write(&self, name: &str, bytes: &[u8]) -> Result<(), RunError> {
        self.record(name)?;
        let path = self.path.join(name);
        swarmpose_data::output::write_file(&path, bytes).map_err(|e| write_error(&path, &e))
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
    /// Creates `name` in `dir`, with a first line `header` if given (a FIFO or a
    /// character device there is written through; a folder there is refused).
    ///
    /// # Errors
    /// An error naming the file.
    pub fn create(dir: &OutputDir, name: &str, header: Option<&str>) -> Result<Self, RunError> {
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
    /// An error naming the file.
    pub fn line(&mut self, text: &str) -> Result<(), RunError> {
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

    /// Appends one CSV record of `fields` ([`csv_record`]) as a line, flushed.
    ///
    /// # Errors
    /// An error naming the file.
    pub fn record<I>(&mut self, fields: I) -> Result<(), RunError>
    where
        I: IntoIterator,
        I::Item: AsRef<[u8]>,
    {
        let line = csv_record(fields).map_err(|e| write_error(&self.path, &e))?;
        self.line(&line)
    }
}

/// The files a run streams frame by frame: `trajectory.kitti.txt`,
/// `trajectory.tum.txt`, `frames.csv` and `motion_covariance.csv` (see
/// [`crate::output`] for their lines), each line flushed as the frame is done.
#[derive(Debug)]
pub struct FrameFiles {
    kitti: StreamFile,
    tum: StreamFile,
    frames: StreamFile,
    covariance: StreamFile,
}

impl FrameFiles {
    /// Creates the files in `dir`, with their headers.
    ///
    /// # Errors
    /// An error naming the file that cannot be created.
    pub fn create(dir: &OutputDir) -> Result<Self, RunError> {
        Ok(Self {
            kitti: StreamFile::create(dir, "trajectory.kitti.txt", None)?,
            tum: StreamFile::create(dir, "trajectory.tum.txt", None)?,
            frames: StreamFile::create(dir, "frames.csv", Some(FRAMES_HEADER))?,
            covariance: StreamFile::create(dir, "motion_covariance.csv", Some(COVARIANCE_HEADER))?,
        })
    }

    /// `frames.csv`, for rows that are not frames (a bag's unpaired images).
    pub fn frames_csv(&mut self) -> &mut StreamFile {
        &mut self.frames
    }

    /// Writes one frame's lines.
    ///
    /// # Errors
    /// An error naming the file that cannot be written.
    pub fn frame(&mut self, r: &FrameResult) -> Result<(), RunError> {
        self.kitti.line(&kitti_line(&r.pose))?;
        self.tum.line(&tum_line(r.timestamp_s, &r.pose))?;
        self.frames.record(frames_row(r))?;
        covariance_row(r).map_or(Ok(()), |row| self.covariance.record(row))
    }
}
