//! Karlsruhe stereo sequences (Geiger et al.): rectified, cropped grayscale pairs
//! `I1_NNNNNN.png` (left) and `I2_NNNNNN.png` (right), in the sequence directory or its
//! `*_Images/` subdirectory, and `calib.txt` whose `P1_roi` / `P2_roi` rows are the
//! projection matrices of the cropped images (baseline from both rows' offsets, `P1_roi[0][3] - P2_roi[0][3] = f b`).
//!
//! `insdata.txt` holds rough GPS/INS poses of the vehicle, not of the camera, with no
//! camera-to-INS extrinsic: it is not returned as camera ground truth.

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use crate::error::DatasetError;
use crate::frames::ListedPairs;
use crate::projection::{Calibration, Row, projection_numbers, rectified_pair};
use crate::text::{KeyLines, numbers_at_least, parse_error, read_text, rows_per_frame, strip_bom};
use crate::{RectifiedStereo, StereoPair, StereoSequence};

fn is_left(name: &str) -> bool {
    name.starts_with("I1_") && crate::text::is_png(name)
}

/// The directory holding the `I1_*.png` images: `dir` or a `*_Images` subdirectory.
fn image_dir(dir: &Path) -> Option<PathBuf> {
    let has = |d: &Path| {
        std::fs::read_dir(d).is_ok_and(|mut rd| {
            rd.any(|e| e.is_ok_and(|e| e.file_name().to_str().is_some_and(is_left)))
        })
    };
    if has(dir) {
        return Some(dir.to_owned());
    }
    let mut subs: Vec<PathBuf> = std::fs::read_dir(dir)
        .ok()?
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_dir())
        .collect();
    subs.sort();
    subs.into_iter().find(|p| has(p))
}

/// True when `dir` looks like a Karlsruhe sequence.
#[must_use]
pub fn detect(dir: &Path) -> bool {
    image_dir(dir).is_some()
}

/// The rectified stereo model of a Karlsruhe `calib.txt` (`P1_roi`, `P2_roi` rows, read
/// in full: [`crate::projection`]), with a note when the baseline is slightly off the
/// rows' axis.
///
/// # Errors
/// [`DatasetError::Parse`] naming the file and line.
pub fn read_calibration(path: &Path) -> Result<Calibration, DatasetError> {
    read_text(path, "Karlsruhe calibration calib.txt")
        .and_then(|text| parse_calibration(&text, path))
}

/// [`read_calibration`] of text already read; messages name `path`.
///
/// # Errors
/// As [`read_calibration`].
pub fn parse_calibration(text: &str, path: &Path) -> Result<Calibration, DatasetError> {
    let (mut p1, mut p2) = (None, None);
    let mut keys = KeyLines::default();
    for (k, line) in strip_bom(text).lines().enumerate() {
        let Some((name, rest)) = line.split_once(':') else {
            continue;
        };
        keys.first(name.trim(), k + 1, path)?;
        let slot = match name.trim() {
            "P1_roi" => &mut p1,
            "P2_roi" => &mut p2,
            _ => continue,
        };
        let v = projection_numbers(rest, path, k + 1)?;
        *slot = Some((v, k + 1));
    }
    let (Some((p1, l1)), Some((p2, l2))) = (p1, p2) else {
        return Err(parse_error(path, 0, "needs the P1_roi: and P2_roi: rows"));
    };
    let row = |name, line, p| Row { name, line, p };
    rectified_pair(path, row("P1_roi", l1, &p1), row("P2_roi", l2, &p2))
}

/// Reads `insdata.txt`: per line, the timestamp (ns) and the local metric position
/// `x, y, z` (columns 5-7, metres) of the vehicle's INS, one line per frame.
///
/// # Errors
/// [`DatasetError::Parse`] naming the file and line.
pub fn read_ins_positions(path: &Path) -> Result<Vec<(u64, [f64; 3])>, DatasetError> {
    let text = read_text(path, "Karlsruhe INS data insdata.txt")?;
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let v = numbers_at_least(line, path, k + 1, 10, |n| {
            format!("expected 10 columns, found {n}")
        })?;
        let ts = line
            .split_whitespace()
            .next()
            .and_then(|t| t.parse::<u64>().ok())
            .ok_or_else(|| parse_error(path, k + 1, "the timestamp is not an integer"))?;
        out.push((ts, [v[4], v[5], v[6]]));
    }
    Ok(out)
}

/// A Karlsruhe sequence.
#[derive(Debug, Clone)]
pub struct KarlsruheSequence {
    images: PathBuf,
    pairs: ListedPairs,
}

impl KarlsruheSequence {
    /// Opens a sequence directory (the drive directory or its image directory).
    ///
    /// # Errors
    /// No images, a count mismatch, a missing or malformed `calib.txt`, an unreadable
    /// first image.
    pub fn open(dir: &Path) -> Result<Self, DatasetError> {
        let images = image_dir(dir).ok_or_else(|| DatasetError::Missing {
            path: dir.join("I1_000000.png"),
            what: "Karlsruhe left images I1_*.png",
        })?;
        let calibration = [dir.join("calib.txt"), images.join("calib.txt")]
            .into_iter()
            .chain(dir.parent().map(|p| p.join("calib.txt")))
            .find(|p| p.is_file())
            .unwrap_or_else(|| dir.join("calib.txt"));
        let (left, right) = ((images.as_path(), "I1_"), (images.as_path(), "I2_"));
        let pairs = ListedPairs::open(dir, left, right, &calibration, read_calibration)?;
        Ok(Self { images, pairs })
    }
}

impl KarlsruheSequence {
    /// The rough INS positions of the vehicle (not the camera), metres, one per frame,
    /// from `insdata.txt` beside the images; `None` when the file is absent. There is no
    /// camera-to-INS extrinsic: compare trajectories after an alignment.
    ///
    /// # Errors
    /// A malformed line, or a line count that differs from the frame count.
    pub fn ins_positions(&self) -> Result<Option<Vec<[f64; 3]>>, DatasetError> {
        let path = self.images.join("insdata.txt");
        let rows = rows_per_frame(&path, self.pairs.left.len(), "rows", read_ins_positions)?;
        Ok(rows.map(|rows| rows.into_iter().map(|r| r.1).collect()))
    }
}

impl StereoSequence for KarlsruheSequence {
    crate::listed_sequence!("karlsruhe");

    fn ground_truth(&self) -> Option<&[Isometry3<f64>]> {
        None
    }
}
