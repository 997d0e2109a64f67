//! Frames are what they are named: the numbered image files of a folder (a gap, a
//! duplicate number or a file that is not a frame is an error naming it), and the
//! pairing of left and right frames (the first frame present on one side only is named).

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use crate::error::DatasetError;
use crate::projection::Calibration;
use crate::text::check_plausible;
use crate::{RectifiedStereo, first_image};

/// One frame of a camera: its number (or timestamp) and its image.
pub(crate) type Listed = (i64, PathBuf);

fn frames_error(path: &Path, message: String) -> DatasetError {
    DatasetError::Frames {
        path: path.to_owned(),
        message,
    }
}

/// The frame number of an image name `PREFIX` + digits + `.png`, or `None` when the name
/// has the prefix and the extension but something else between (not a frame).
fn frame_number(name: &str, prefix: &str) -> Option<i64> {
    let stem = name.strip_prefix(prefix)?;
    let digits = stem.get(..stem.len().checked_sub(4)?)?;
    if digits.is_empty() || !digits.bytes().all(|b| b.is_ascii_digit()) {
        return None;
    }
    digits.parse().ok()
}

/// The PNG images of `dir` whose names start with `prefix`, ordered by frame number.
///
/// # Errors
/// [`DatasetError::Frames`] naming the first file that is not `PREFIX` + digits + `.png`,
/// a number given twice (both files named) or the first number missing between two
/// frames; [`DatasetError::Io`] when `dir` cannot be listed.
pub(crate) fn list_numbered(dir: &Path, prefix: &str) -> Result<Vec<Listed>, DatasetError> {
    let io = |source| DatasetError::Io {
        path: dir.to_owned(),
        source,
    };
    let mut names = Vec::new();
    for e in std::fs::read_dir(dir).map_err(io)? {
        let e = e.map_err(io)?;
        let Some(name) = e.file_name().to_str().map(str::to_owned) else {
            continue;
        };
        if name.starts_with(prefix) && crate::text::is_png(&name) {
            names.push(name);
        }
    }
    names.sort();
    let mut out = Vec::with_capacity(names.len());
    for name in names {
        let path = dir.join(&name);
        let n = frame_number(&name, prefix).ok_or_else(|| {
            frames_error(
                &path,
                format!(
                    "not a frame image (expected {prefix}NNNNNN.png, the frame number in \
                     digits): move it out of the folder"
                ),
            )
        })?;
        out.push((n, path));
    }
    out.sort_by(|a, b| a.0.cmp(&b.0).then_with(|| a.1.cmp(&b.1)));
    for w in out.windows(2) {
        let ((a, pa), (b, pb)) = (&w[0], &w[1]);
        if a == b {
            return Err(frames_error(
                pb,
                format!("frame number {b} again (also {})", pa.display()),
            ));
        }
        if *b != a + 1 {
            let width = pa
                .file_name()
                .and_then(|n| n.to_str())
                .map_or(0, |n| n.len().saturating_sub(prefix.len() + 4));
            return Err(frames_error(
                &dir.join(format!("{prefix}{:0width$}.png", a + 1)),
                format!(
                    "missing: frame {} comes after frame {a} ({}); frames must be numbered \
                     without gaps",
                    b,
                    pb.display()
                ),
            ));
        }
    }
    Ok(out)
}

/// Checks that `left` and `right` list the same frames (numbers or timestamps) and are
/// not empty.
///
/// # Errors
/// [`DatasetError::Unpaired`] naming the first frame present on one side only;
/// [`DatasetError::Empty`] when there is no frame.
pub(crate) fn check_pairs(
    dir: &Path,
    left: &[Listed],
    left_dir: &Path,
    right: &[Listed],
    right_dir: &Path,
) -> Result<(), DatasetError> {
    let keys = |l: &[Listed]| l.iter().map(|x| x.0).collect::<BTreeSet<i64>>();
    let (lk, rk) = (keys(left), keys(right));
    let only_left = left.iter().find(|x| !rk.contains(&x.0));
    let only_right = right.iter().find(|x| !lk.contains(&x.0));
    let first = match (only_left, only_right) {
        (Some(l), Some(r)) => Some(if r.0 < l.0 {
            (r, left_dir)
        } else {
            (l, right_dir)
        }),
        (Some(l), None) => Some((l, right_dir)),
        (None, Some(r)) => Some((r, left_dir)),
        (None, None) => None,
    };
    if let Some(((key, path), other)) = first {
        return Err(DatasetError::Unpaired {
            present: path.clone(),
            key: *key,
            other: other.to_owned(),
            left: left.len(),
            right: right.len(),
        });
    }
    if left.is_empty() {
        return Err(DatasetError::Empty {
            dir: dir.to_owned(),
        });
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frame_numbers_of_names() {
        assert_eq!(frame_number("000042.png", ""), Some(42));
        assert_eq!(frame_number("I1_000042.PNG", "I1_"), Some(42));
        assert_eq!(frame_number("000003_copy.png", ""), None);
        assert_eq!(frame_number(".png", ""), None);
        assert_eq!(frame_number("x.png", ""), None);
    }
}

/// A sequence of numbered left and right image files and a calibration file: what the
/// KITTI and Karlsruhe layouts share.
#[derive(Debug, Clone)]
pub(crate) struct ListedPairs {
    /// The sequence directory.
    pub(crate) root: PathBuf,
    /// The left and right images of each frame, in frame order.
    pub(crate) left: Vec<PathBuf>,
    pub(crate) right: Vec<PathBuf>,
    /// The rectified stereo model of the calibration file.
    pub(crate) rig: RectifiedStereo,
    /// Width and height of the first left image, pixels.
    pub(crate) size: (usize, usize),
    /// Warnings about the calibration and the first image.
    pub(crate) notes: Vec<String>,
}

impl ListedPairs {
    /// The sequence at `root` of the images `(folder, name prefix)` numbered alike
    /// ([`list_numbered`], [`check_pairs`]), with the rig of the file `calibration` read
    /// by `read_calibration`, checked against the first left image's size.
    ///
    /// # Errors
    /// No images or unmatched numbers, a missing or malformed calibration, an unreadable
    /// first image, or a rig implausible for its size.
    pub(crate) fn open(
        root: &Path,
        (left_dir, left_prefix): (&Path, &str),
        (right_dir, right_prefix): (&Path, &str),
        calibration: &Path,
        read_calibration: fn(&Path) -> Result<Calibration, DatasetError>,
    ) -> Result<Self, DatasetError> {
        let left = list_numbered(left_dir, left_prefix)?;
        let right = list_numbered(right_dir, right_prefix)?;
        check_pairs(root, &left, left_dir, &right, right_dir)?;
        let left: Vec<PathBuf> = left.into_iter().map(|x| x.1).collect();
        let right: Vec<PathBuf> = right.into_iter().map(|x| x.1).collect();
        let (rig, note) = read_calibration(calibration)?;
        let (size, mut notes) = first_image(&left[0])?;
        check_plausible(calibration, &rig, size)?;
        notes.extend(note);
        Ok(Self {
            root: root.to_owned(),
            left,
            right,
            rig,
            size,
            notes,
        })
    }
}
