//! One item of a batch: run as `swarmpose odometry` runs it (the same function, in this
//! process), into `OUT/<item>/`, with its console output in `log.txt` and its
//! `summary.json`; or skipped when its summary says it is done with the same input,
//! options and version.

use std::fs::{File, OpenOptions, TryLockError};
use std::panic::{AssertUnwindSafe, catch_unwind};
use std::path::Path;
use std::time::Instant;

use serde::{Deserialize, Serialize};

use super::hashes::{VERSION, config_hash, item_input_hash, odometry_args};
use super::manifest::Item;
use crate::commands::odometry::run_command;
use crate::error::{CliError, EXIT_NOT_USABLE};
use crate::output_file::write_bytes;
use crate::streams::capture;

/// Name of an item's summary in its folder.
pub const SUMMARY: &str = "summary.json";
/// Name of an item's console output in its folder.
pub const LOG: &str = "log.txt";
/// Lock of an item's folder held by the batch that runs it (beside the run's own).
const ITEM_LOCK: &str = ".swarmpose-batch-lock";

/// How an item ended.
pub const STATUS_OK: &str = "ok";
/// The run finished but fewer than half of its motions were tracked (exit status 3).
pub const STATUS_NOT_USABLE: &str = "not-usable";
/// Stopped by SIGINT/SIGTERM (exit status 130/143): rerun.
pub const STATUS_STOPPED: &str = "stopped";
/// Any other failure (bad input, an unwritable output): rerun.
pub const STATUS_FAILED: &str = "failed";

/// The figures of an evaluation against the sequence's ground truth.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Metrics {
    /// Ground-truth path length, metres.
    pub path_length_m: f64,
    /// Final position error, metres.
    pub final_drift_m: f64,
    /// The same, percent of the path (none for a path under 10 cm).
    pub final_drift_percent: Option<f64>,
    /// RMS of eq. (20) between consecutive frames.
    pub eq20_rms: f64,
    /// ATE after SE(3) alignment, RMS, metres.
    pub ate_aligned_m: f64,
    /// RPE translation, RMS, metres.
    pub rpe_translation_m: f64,
    /// RPE rotation, RMS, degrees.
    pub rpe_rotation_deg: f64,
    /// KITTI segment translation error, percent (none when the path is too short).
    pub kitti_translation_percent: Option<f64>,
    /// KITTI segment rotation error, degrees per 100 m.
    pub kitti_rotation_deg_per_100m: Option<f64>,
}

/// `summary.json`: what a batch item did.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Summary {
    /// The item's name.
    pub item: String,
    /// [`STATUS_OK`], [`STATUS_NOT_USABLE`], [`STATUS_STOPPED`] or [`STATUS_FAILED`].
    pub status: String,
    /// The exit status `swarmpose odometry` would have had.
    pub exit_code: u8,
    /// Its error message, if any.
    pub message: Option<String>,
    /// The input, as the manifest resolved it.
    pub input: String,
    /// The item's `swarmpose odometry` options.
    pub args: Vec<String>,
    /// Frames written to `frames.csv`.
    pub frames: usize,
    /// Frames whose motion was tracked.
    pub tracked: usize,
    /// Frames held at constant velocity.
    pub constant_velocity: usize,
    /// Frames lost.
    pub lost: usize,
    /// Against the ground truth, when the sequence has one and the run finished.
    pub metrics: Option<Metrics>,
    /// Wall time of the run, seconds.
    pub time_s: f64,
    /// [`input_hash`](super::hashes::input_hash).
    pub input_hash: String,
    /// [`config_hash`].
    pub config_hash: String,
    /// The swarmpose version.
    pub version: String,
}

impl Summary {
    /// Whether the item finished (usable or not): a rerun with the same hashes skips it.
    #[must_use]
    pub fn finished(&self) -> bool {
        self.status == STATUS_OK || self.status == STATUS_NOT_USABLE
    }
}

/// What happened to an item in this batch.
#[derive(Debug, Clone, PartialEq)]
pub enum Outcome {
    /// Run now; its summary.
    Ran(Summary),
    /// Done before with the same input, options and version; its summary.
    Skipped(Summary),
    /// Another batch holds its folder: nothing done.
    Busy(String),
}

/// Reads `dir/summary.json`, if it is there and readable.
#[must_use]
pub fn read_summary(dir: &Path) -> Option<Summary> {
    let text = std::fs::read_to_string(dir.join(SUMMARY)).ok()?;
    serde_json::from_str(&text).ok()
}

/// Locks `dir` for this batch; `None` when another holds it.
fn lock(dir: &Path) -> Result<Option<File>, CliError> {
    let path = dir.join(ITEM_LOCK);
    let file = OpenOptions::new()
        .write(true)
        .create(true)
        .truncate(false)
        .open(&path)
        .map_err(|e| crate::output_file::write_error(&path, &e))?;
    match file.try_lock() {
        Ok(()) => Ok(Some(file)),
        Err(TryLockError::WouldBlock) => Ok(None),
        Err(TryLockError::Error(e)) => Err(crate::output_file::write_error(&path, &e)),
    }
}

/// Counts of `frames.csv`'s statuses: frames, tracked, constant velocity, lost.
fn frame_counts(dir: &Path) -> [usize; 4] {
    let text = std::fs::read_to_string(dir.join("frames.csv")).unwrap_or_default();
    let mut c = [0; 4];
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes());
    for record in reader.records() {
        let status = record.as_ref().ok().and_then(|r| r.get(2)).unwrap_or("");
        c[0] += 1;
        let k = [(1, "tracked"), (2, "constant-velocity"), (3, "lost")]
            .into_iter()
            .find(|(_, s)| status.starts_with(s));
        if let Some((k, _)) = k {
            c[k] += 1;
        }
    }
    c
}

/// The figures of `dir/evaluation.json`, if the run wrote one.
fn metrics(dir: &Path) -> Option<Metrics> {
    let text = std::fs::read_to_string(dir.join("evaluation.json")).ok()?;
    let v: serde_json::Value = serde_json::from_str(&text).ok()?;
    let f = |p: &str| v.pointer(p).and_then(serde_json::Value::as_f64);
    Some(Metrics {
        path_length_m: f("/path_length_m")?,
        final_drift_m: f("/final_drift_m")?,
        final_drift_percent: f("/final_drift_percent"),
        eq20_rms: f("/eq20_rms")?,
        ate_aligned_m: f("/ate_aligned/rmse")?,
        rpe_translation_m: f("/rpe_translation/rmse")?,
        rpe_rotation_deg: f("/rpe_rotation_deg/rmse")?,
        kitti_translation_percent: f("/kitti/translation_percent"),
        kitti_rotation_deg_per_100m: f("/kitti/rotation_deg_per_100m"),
    })
}

/// The status of an exit code.
fn status_of(code: u8) -> &'static str {
    match code {
        0 => STATUS_OK,
        EXIT_NOT_USABLE => STATUS_NOT_USABLE,
        130 | 143 => STATUS_STOPPED,
        _ => STATUS_FAILED,
    }
}

/// `run_command` on `args`, its console output captured; a panic (a bug) is an item's
/// failure, not the batch's.
fn run_captured(args: &crate::commands::odometry::OdometryArgs) -> (Result<(), CliError>, String) {
    capture(|| {
        catch_unwind(AssertUnwindSafe(|| run_command(args))).unwrap_or_else(|_| {
            Err(CliError::failure(
                "internal error (a bug): the run panicked",
            ))
        })
    })
}

/// The hashes of an item, or why they cannot be made.
struct Hashes {
    input: String,
    config: String,
}

/// An item's summary from how its run ended (the counts and figures are read from its
/// folder).
fn summary_of(
    item: &Item,
    dir: &Path,
    end: &Result<(), CliError>,
    time_s: f64,
    h: Hashes,
) -> Summary {
    let (exit_code, message) = match end {
        Ok(()) => (0, None),
        Err(e) => (e.code, Some(e.message.clone()).filter(|m| !m.is_empty())),
    };
    let status = status_of(exit_code);
    let [frames, tracked, constant_velocity, lost] = frame_counts(dir);
    Summary {
        item: item.name.clone(),
        status: status.to_owned(),
        exit_code,
        message,
        input: item.input.to_string_lossy().into_owned(),
        args: item.args.clone(),
        frames,
        tracked,
        constant_velocity,
        lost,
        metrics: (status == STATUS_OK || status == STATUS_NOT_USABLE)
            .then(|| metrics(dir))
            .flatten(),
        time_s,
        input_hash: h.input,
        config_hash: h.config,
        version: VERSION.to_owned(),
    }
}

/// Writes `log.txt` and then `summary.json` (each whole, under a temporary name first).
fn write_summary(dir: &Path, summary: &Summary, console: &str) -> Result<(), CliError> {
    write_bytes(&dir.join(LOG), console.as_bytes())?;
    let json = serde_json::to_string_pretty(summary)
        .map_err(|e| CliError::failure(format!("{SUMMARY}: {e}")))?;
    write_bytes(&dir.join(SUMMARY), json.as_bytes())
}

/// Runs `item` into `out/<name>/`, unless its summary there says it finished with the
/// same hashes. An item that cannot run (bad options, an unreadable input) gets a
/// summary that says so, as one that fails while it runs.
///
/// # Errors
/// Exit status 1 when the item's folder cannot be made, locked or written.
pub fn run_item(item: &Item, out: &Path) -> Result<Outcome, CliError> {
    let dir = out.join(&item.name);
    std::fs::create_dir_all(&dir).map_err(|e| crate::output_file::write_error(&dir, &e))?;
    let Some(_lock) = lock(&dir)? else {
        return Ok(Outcome::Busy(format!(
            "{}: in use by another batch",
            dir.display()
        )));
    };
    let prepared = odometry_args(item, &dir).and_then(|args| {
        let h = Hashes {
            config: config_hash(item)?,
            input: item_input_hash(item)?,
        };
        Ok((args, h))
    });
    let (args, h) = match prepared {
        Ok(p) => p,
        Err(e) => {
            let h = Hashes {
                input: String::new(),
                config: String::new(),
            };
            let console = format!("swarmpose: error: {}\n", e.message);
            let summary = summary_of(item, &dir, &Err(e), 0.0, h);
            write_summary(&dir, &summary, &console)?;
            return Ok(Outcome::Ran(summary));
        }
    };
    if let Some(s) = read_summary(&dir)
        && s.finished()
        && s.input_hash == h.input
        && s.config_hash == h.config
        && s.version == VERSION
    {
        return Ok(Outcome::Skipped(s));
    }
    // A summary left by an earlier run must not outlive the outputs it describes.
    let old = dir.join(SUMMARY);
    if std::fs::symlink_metadata(&old).is_ok_and(|m| m.is_file()) {
        std::fs::remove_file(&old).map_err(|e| crate::output_file::write_error(&old, &e))?;
    }
    let start = Instant::now();
    let (end, mut console) = run_captured(&args);
    let time_s = start.elapsed().as_secs_f64();
    if let Err(e) = &end
        && !e.message.is_empty()
    {
        console.push_str(&format!("swarmpose: error: {}\n", e.message));
    }
    let summary = summary_of(item, &dir, &end, time_s, h);
    write_summary(&dir, &summary, &console)?;
    Ok(Outcome::Ran(summary))
}
