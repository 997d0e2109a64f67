//! Trajectory files: KITTI (one row-major 3x4 `[R | t]` per line, associated by line)
//! and TUM (`timestamp tx ty tz qx qy qz qw`, associated by timestamp).
//!
//! Blank lines and lines starting with `#` are skipped in both; numbers may be
//! separated by spaces, tabs or commas. Rotation matrices read from KITTI files are
//! projected to the nearest rotation; TUM quaternions are normalised (a quaternion far
//! from unit length is an error).

use std::fmt::Write as _;
use std::path::{Path, PathBuf};

use nalgebra::{Isometry3, Matrix3, Quaternion, Rotation3, Translation3, UnitQuaternion};

use crate::error::EvalError;

/// A file format of trajectories.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Format {
    /// KITTI odometry poses: 12 numbers per line, the row-major 3x4 `[R | t]`.
    Kitti,
    /// TUM RGB-D: `timestamp tx ty tz qx qy qz qw` per line.
    Tum,
}

impl Format {
    /// `kitti` or `tum`.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Format::Kitti => "kitti",
            Format::Tum => "tum",
        }
    }

    /// The format a file name suggests: `*.tum.txt`/`*.tum` or a TUM-style name
    /// (`groundtruth.txt`) is TUM, anything else KITTI.
    #[must_use]
    pub fn guess(path: &Path) -> Self {
        let name = path
            .file_name()
            .and_then(|n| n.to_str())
            .unwrap_or_default()
            .to_ascii_lowercase();
        if name.ends_with(".tum.txt") || name.ends_with(".tum") || name == "groundtruth.txt" {
            Format::Tum
        } else {
            Format::Kitti
        }
    }
}

/// Poses in order, with a timestamp each (seconds; for KITTI files the line index).
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// Timestamps, seconds (KITTI: the 0-based line index of the pose).
    pub stamps: Vec<f64>,
    /// Poses: camera (or body) to world, `p_world = pose * p_camera`.
    pub poses: Vec<Isometry3<f64>>,
    /// Where it came from (a file name), for messages.
    pub name: String,
}

impl Trajectory {
    /// A trajectory of `poses` stamped with their indices.
    #[must_use]
    pub fn indexed(name: impl Into<String>, poses: Vec<Isometry3<f64>>) -> Self {
        Self {
            stamps: (0..poses.len()).map(|i| i as f64).collect(),
            poses,
            name: name.into(),
        }
    }

    /// Number of poses.
    #[must_use]
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// True when there is no pose.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// Reads a trajectory file in `format`.
    ///
    /// # Errors
    /// [`EvalError::Io`], [`EvalError::Parse`] naming the line, [`EvalError::Empty`].
    pub fn read(path: &Path, format: Format) -> Result<Self, EvalError> {
        let text = std::fs::read_to_string(path).map_err(|source| EvalError::Io {
            path: path.to_owned(),
            what: "cannot read",
            source,
        })?;
        Self::parse(&text, path, format)
    }

    /// Parses the text of a trajectory file; `path` names it in errors.
    ///
    /// # Errors
    /// As [`Trajectory::read`], without I/O.
    pub fn parse(text: &str, path: &Path, format: Format) -> Result<Self, EvalError> {
        // A UTF-8 byte-order mark is accepted, as by every reader.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let mut stamps = Vec::new();
        let mut poses = Vec::new();
        for (k, line) in text.lines().enumerate() {
            let line_no = k + 1;
            let t = line.trim();
            if t.is_empty() || t.starts_with('#') {
                continue;
            }
            let values = numbers(t, path, line_no)?;
            match format {
                Format::Kitti => {
                    if values.len() != 12 {
                        return Err(EvalError::parse(
                            path,
                            line_no,
                            format!(
                                "a KITTI pose line has 12 numbers (row-major 3x4 [R|t]), this one has {}",
                                values.len()
                            ),
                        ));
                    }
                    stamps.push(poses.len() as f64);
                    poses.push(pose_from_3x4(&values, path, line_no)?);
                }
                Format::Tum => {
                    if values.len() != 8 {
                        return Err(EvalError::parse(
                            path,
                            line_no,
                            format!(
                                "a TUM pose line has 8 numbers (timestamp tx ty tz qx qy qz qw), this one has {}",
                                values.len()
                            ),
                        ));
                    }
                    let q = Quaternion::new(values[7], values[4], values[5], values[6]);
                    let n = q.norm();
                    if !(0.9..=1.1).contains(&n) {
                        return Err(EvalError::parse(
                            path,
                            line_no,
                            format!("quaternion of norm {n:.4}, not a rotation"),
                        ));
                    }
                    if let Some(&last) = stamps.last()
                        && values[0] <= last
                    {
                        return Err(EvalError::parse(
                            path,
                            line_no,
                            format!(
                                "timestamp {} does not increase (previous {last})",
                                values[0]
                            ),
                        ));
                    }
                    stamps.push(values[0]);
                    poses.push(Isometry3::from_parts(
                        Translation3::new(values[1], values[2], values[3]),
                        UnitQuaternion::from_quaternion(q),
                    ));
                }
            }
        }
        if poses.is_empty() {
            return Err(EvalError::Empty {
                path: path.to_owned(),
            });
        }
        Ok(Self {
            stamps,
            poses,
            name: path.display().to_string(),
        })
    }

    /// The file text in `format` (TUM uses [`Trajectory::stamps`]).
    #[must_use]
    pub fn to_text(&self, format: Format) -> String {
        match format {
            Format::Kitti => kitti_text(&self.poses),
            Format::Tum => tum_text(&self.stamps, &self.poses),
        }
    }

    /// Writes the trajectory in `format`.
    ///
    /// # Errors
    /// [`EvalError::Io`] naming the file.
    pub fn write(&self, path: &Path, format: Format) -> Result<(), EvalError> {
        write_text(path, &self.to_text(format))
    }
}

/// Writes `text` to `path`.
///
/// # Errors
/// [`EvalError::Io`] naming the file.
pub fn write_text(path: &Path, text: &str) -> Result<(), EvalError> {
    std::fs::write(path, text).map_err(|source| EvalError::Io {
        path: PathBuf::from(path),
        what: "cannot write",
        source,
    })
}

fn numbers(line: &str, path: &Path, line_no: usize) -> Result<Vec<f64>, EvalError> {
    line.split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(EvalError::parse(
                path,
                line_no,
                format!("'{s}' is not a finite number"),
            )),
        })
        .collect()
}

/// Checks that `r` is a rotation to within rounding: not a reflection (determinant
/// below 0) and `|R Rᵀ - I| <= 1e-2` (the Frobenius norm). Every reader of poses (files,
/// and arrays from Python) uses it, so that a scaled, sheared or zero block is refused
/// rather than projected to some rotation.
///
/// # Errors
/// What is wrong, with the value (the caller names where the block comes from).
pub fn check_rotation(r: &Matrix3<f64>) -> Result<(), String> {
    let err = (r * r.transpose() - Matrix3::identity()).norm();
    let det = r.determinant();
    if det < 0.0 {
        return Err(format!(
            "the 3x3 part has determinant {det:.3} (a reflection): a rotation has +1"
        ));
    }
    if err.is_nan() || err > 1e-2 {
        return Err(format!(
            "the 3x3 part is not a rotation (|R Rᵀ - I| = {err:.3e}, at most 1e-2 accepted)"
        ));
    }
    Ok(())
}

fn pose_from_3x4(m: &[f64], path: &Path, line_no: usize) -> Result<Isometry3<f64>, EvalError> {
    let r = Matrix3::new(m[0], m[1], m[2], m[4], m[5], m[6], m[8], m[9], m[10]);
    check_rotation(&r).map_err(|message| EvalError::parse(path, line_no, message))?;
    let rot = Rotation3::from_matrix_eps(&r, 1e-15, 100, Rotation3::identity());
    Ok(Isometry3::from_parts(
        Translation3::new(m[3], m[7], m[11]),
        UnitQuaternion::from_rotation_matrix(&rot),
    ))
}

/// KITTI text of `poses`: per line the row-major 3x4 `[R | t]`, full precision.
#[must_use]
pub fn kitti_text(poses: &[Isometry3<f64>]) -> String {
    let mut s = String::new();
    for p in poses {
        let r = p.rotation.to_rotation_matrix().into_inner();
        let t = p.translation.vector;
        let row = |i: usize| format!("{:e} {:e} {:e} {:e}", r[(i, 0)], r[(i, 1)], r[(i, 2)], t[i]);
        let _ = writeln!(s, "{} {} {}", row(0), row(1), row(2));
    }
    s
}

/// A timestamp in seconds as text: at least 6 decimals (microseconds, as TUM files have
/// them), more where 6 would move the stamp by more than a few of its last bits, so
/// frames microseconds or less apart never get the same stamp (`--frame-period 1e-7`
/// wrote `0.000000` twice) and a stamp reads back as the value written.
#[must_use]
pub fn stamp_text(t: f64) -> String {
    if !t.is_finite() {
        return t.to_string();
    }
    let tolerance = 4.0 * f64::EPSILON * t.abs();
    for decimals in 6..=40 {
        let s = format!("{t:.decimals$}");
        if s.parse::<f64>()
            .is_ok_and(|back| (back - t).abs() <= tolerance)
        {
            return s;
        }
    }
    // Shorter than 1e-40 s: the shortest text that reads back exactly.
    t.to_string()
}

/// TUM text: `timestamp tx ty tz qx qy qz qw` per pose (`qw >= 0`).
///
/// Pairs `stamps` and `poses` up to the shorter of the two.
#[must_use]
pub fn tum_text(stamps: &[f64], poses: &[Isometry3<f64>]) -> String {
    let mut s = String::new();
    for (t, p) in stamps.iter().zip(poses) {
        let [w, x, y, z] = swarmpose_core::geometry::quaternion_wxyz(&p.rotation);
        let v = p.translation.vector;
        let _ = writeln!(
            s,
            "{} {:e} {:e} {:e} {x:e} {y:e} {z:e} {w:e}",
            stamp_text(*t),
            v.x,
            v.y,
            v.z
        );
    }
    s
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn sample() -> Vec<Isometry3<f64>> {
        (0..5)
            .map(|i| {
                let f = i as f64;
                Isometry3::new(
                    Vector3::new(f, 0.1 * f * f, -0.3 * f),
                    Vector3::new(0.01 * f, -0.2 * f, 0.05),
                )
            })
            .collect()
    }

    #[test]
    fn stamps_of_short_frame_periods_stay_apart() {
        // Microsecond stamps as TUM writes them stay as they were.
        assert_eq!(stamp_text(0.1 * 3.0), "0.300000");
        assert_eq!(stamp_text(1_403_636_579.763_555_5), "1403636579.763556");
        assert_eq!(stamp_text(0.0), "0.000000");
        // Frames 100 ns apart were written as 0.000000, 0.000000, ...
        for period in [1e-7, 3.3e-9, 1.25e-12] {
            let texts: Vec<String> = (0..50).map(|i| stamp_text(f64::from(i) * period)).collect();
            for (i, t) in texts.iter().enumerate() {
                let back: f64 = t.parse().expect("a number");
                assert!(
                    (back - f64::from(i as u32) * period).abs() <= 1e-3 * period,
                    "{t}"
                );
            }
            let mut unique = texts.clone();
            unique.dedup();
            assert_eq!(unique.len(), texts.len(), "{texts:?}");
        }
    }

    #[test]
    fn kitti_round_trip() {
        let poses = sample();
        let text = kitti_text(&poses);
        let t = Trajectory::parse(&text, Path::new("x.txt"), Format::Kitti).expect("parse");
        assert_eq!(t.len(), 5);
        for (a, b) in poses.iter().zip(&t.poses) {
            assert!((a.to_homogeneous() - b.to_homogeneous()).norm() < 1e-14);
        }
        assert_eq!(t.stamps, vec![0.0, 1.0, 2.0, 3.0, 4.0]);
    }

    #[test]
    fn tum_round_trip() {
        let poses = sample();
        let stamps: Vec<f64> = (0..5).map(|i| 100.0 + 0.1 * i as f64).collect();
        let text = tum_text(&stamps, &poses);
        let t = Trajectory::parse(&text, Path::new("x.tum.txt"), Format::Tum).expect("parse");
        for (a, b) in poses.iter().zip(&t.poses) {
            assert!((a.to_homogeneous() - b.to_homogeneous()).norm() < 1e-12);
        }
        assert!((t.stamps[3] - 100.3).abs() < 1e-9);
    }

    #[test]
    fn errors_name_file_and_line() {
        let poses = sample();
        let mut text = kitti_text(&poses);
        text.push_str("1 0 0 0 0 1 0 0 0 0 1\n"); // truncated: 11 numbers
        let e = Trajectory::parse(&text, Path::new("est.txt"), Format::Kitti).expect_err("bad");
        let msg = e.to_string();
        assert!(msg.starts_with("est.txt:6: "), "{msg}");
        assert!(msg.contains("has 11"), "{msg}");
        let e = Trajectory::parse("1 2 x 4 0 0 0 1\n", Path::new("g"), Format::Tum)
            .expect_err("not a number");
        assert!(e.to_string().contains("g:1: 'x'"), "{e}");
        let e = Trajectory::parse("# only\n\n", Path::new("g"), Format::Tum).expect_err("empty");
        assert!(matches!(e, EvalError::Empty { .. }));
        let e = Trajectory::parse("0 0 0 0 0 0 0 2\n", Path::new("g"), Format::Tum)
            .expect_err("norm 2");
        assert!(e.to_string().contains("norm"), "{e}");
        let e = Trajectory::parse("2 0 0 0 1 0 0 0 1 0 0 0\n", Path::new("k"), Format::Kitti)
            .expect_err("not a rotation");
        assert!(e.to_string().contains("not a rotation"), "{e}");
    }

    #[test]
    fn guesses_format() {
        assert_eq!(
            Format::guess(Path::new("a/trajectory.tum.txt")),
            Format::Tum
        );
        assert_eq!(Format::guess(Path::new("groundtruth.txt")), Format::Tum);
        assert_eq!(Format::guess(Path::new("poses.txt")), Format::Kitti);
    }
}
