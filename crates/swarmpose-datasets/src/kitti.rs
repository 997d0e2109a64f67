//! KITTI odometry layout: `image_0/` (left) and `image_1/` (right) rectified grayscale
//! PNGs, `calib.txt` with `P0:` and `P1:` 3x4 projection rows (the baseline comes from
//! the two rows' offsets, `P0[0][3] - P1[0][3] = fx b`), and ground truth as row-major 3x4 `[R | t]` lines (`poses.txt`
//! in the sequence directory, or `poses/NN.txt` of the official tree).

use std::path::{Path, PathBuf};

use nalgebra::Isometry3;

use crate::error::DatasetError;
use crate::frames::ListedPairs;
use crate::projection::{Calibration, Row, projection_numbers, rectified_pair};
use crate::text::{KeyLines, numbers, parse_error, read_text, rows_per_frame, strip_bom};
use crate::{RectifiedStereo, StereoPair, StereoSequence, pose_from_3x4};

/// True when `dir` looks like a KITTI sequence.
#[must_use]
pub fn detect(dir: &Path) -> bool {
    dir.join("image_0").is_dir() && dir.join("image_1").is_dir()
}

/// A KITTI odometry sequence.
#[derive(Debug, Clone)]
pub struct KittiSequence {
    pairs: ListedPairs,
    poses: Option<Vec<Isometry3<f64>>>,
}

/// The rectified stereo model of a KITTI `calib.txt` (`P0:`/`P1:` rows; two unprefixed
/// rows are read as P0 and P1), read in full ([`crate::projection`]: both rows' offsets
/// give the baseline), with a note when the baseline is slightly off the rows' axis.
///
/// # Errors
/// [`DatasetError::Parse`] naming the file and line of a malformed row or a missing one.
pub fn read_calibration(path: &Path) -> Result<Calibration, DatasetError> {
    read_text(path, "KITTI calibration calib.txt").and_then(|text| parse_calibration(&text, path))
}

/// [`read_calibration`] of text already read; messages name `path`.
///
/// # Errors
/// As [`read_calibration`].
pub fn parse_calibration(text: &str, path: &Path) -> Result<Calibration, DatasetError> {
    let (mut p0, mut p1) = (None, None);
    let mut unnamed = Vec::new();
    let mut keys = KeyLines::default();
    for (k, line) in strip_bom(text).lines().enumerate() {
        let line_no = k + 1;
        let line = line.trim();
        if line.is_empty() {
            continue;
        }
        let (name, rest) = match line.split_once(':') {
            Some((n, r)) => (Some(n.trim()), r),
            None => (None, line),
        };
        if let Some(n) = name {
            keys.first(n, line_no, path)?;
        }
        let slot = match name {
            Some("P0") => &mut p0,
            Some("P1") => &mut p1,
            Some(_) => continue,
            None => {
                unnamed.push(line_no);
                if unnamed.len() == 1 {
                    &mut p0
                } else if unnamed.len() == 2 {
                    &mut p1
                } else {
                    continue;
                }
            }
        };
        let v = projection_numbers(rest, path, line_no)?;
        if slot.is_some() {
            // An unnamed row beside a named one of the same slot.
            return Err(parse_error(
                path,
                line_no,
                "P0/P1 given both by name and as an unnamed row: keep one",
            ));
        }
        *slot = Some((v, line_no));
    }
    let (Some((p0, l0)), Some((p1, l1))) = (p0, p1) else {
        return Err(parse_error(
            path,
            0,
            "needs the P0: and P1: projection rows",
        ));
    };
    let row = |name, line, p| Row { name, line, p };
    rectified_pair(path, row("P0", l0, &p0), row("P1", l1, &p1))
}

/// Reads row-major 3x4 poses, one per line.
///
/// # Errors
/// [`DatasetError::Parse`] naming the file and line.
pub fn read_poses(path: &Path) -> Result<Vec<Isometry3<f64>>, DatasetError> {
    let text = read_text(path, "ground-truth poses")?;
    parse_poses(&text, path)
}

/// [`read_poses`] of text already read; messages name `path`.
///
/// # Errors
/// As [`read_poses`].
pub fn parse_poses(text: &str, path: &Path) -> Result<Vec<Isometry3<f64>>, DatasetError> {
    let mut out = Vec::new();
    for (k, line) in text.lines().enumerate() {
        if line.trim().is_empty() {
            continue;
        }
        let v = numbers(line, path, k + 1)?;
        if v.len() != 12 {
            return Err(parse_error(
                path,
                k + 1,
                format!("a 3x4 pose needs 12 numbers, found {}", v.len()),
            ));
        }
        let r = nalgebra::Matrix3::new(v[0], v[1], v[2], v[4], v[5], v[6], v[8], v[9], v[10]);
        let off = (r * r.transpose() - nalgebra::Matrix3::identity()).norm();
        let det = r.determinant();
        if det < 0.0 {
            return Err(parse_error(
                path,
                k + 1,
                format!("the 3x3 part has determinant {det:.3} (a reflection): a rotation has +1"),
            ));
        }
        if off > 1e-2 {
            return Err(parse_error(
                path,
                k + 1,
                format!(
                    "the 3x3 part is not a rotation (|R Rᵀ - I| = {off:.3e}, at most 1e-2 \
                     accepted)"
                ),
            ));
        }
        out.push(pose_from_3x4(&v));
    }
    Ok(out)
}

impl KittiSequence {
    /// Opens a KITTI sequence directory.
    ///
    /// # Errors
    /// Missing directories or calibration, a malformed calibration or pose line, a
    /// left/right count mismatch, an unreadable first image.
    pub fn open(dir: &Path) -> Result<Self, DatasetError> {
        let (ld, rd) = (dir.join("image_0"), dir.join("image_1"));
        for d in [&ld, &rd] {
            if !d.is_dir() {
                return Err(DatasetError::Missing {
                    path: d.clone(),
                    what: "KITTI image directory",
                });
            }
        }
        let calibration = dir.join("calib.txt");
        let pairs = ListedPairs::open(dir, (&ld, ""), (&rd, ""), &calibration, read_calibration)?;
        let pose_file = official_poses(dir).unwrap_or_else(|| dir.join("poses.txt"));
        let poses = rows_per_frame(&pose_file, pairs.left.len(), "poses", read_poses)?;
        Ok(Self { pairs, poses })
    }
}

/// `../../poses/NN.txt` for an official `sequences/NN` directory, when it exists.
fn official_poses(dir: &Path) -> Option<PathBuf> {
    let name = dir.file_name()?;
    let p = dir
        .parent()?
        .parent()?
        .join("poses")
        .join(name)
        .with_extension("txt");
    p.is_file().then_some(p)
}

impl StereoSequence for KittiSequence {
    crate::listed_sequence!("kitti");

    fn ground_truth(&self) -> Option<&[Isometry3<f64>]> {
        self.poses.as_deref()
    }
}
