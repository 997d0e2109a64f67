//! A rectified stereo rig from the two 3x4 projection rows of a calibration file (KITTI's
//! `P0`/`P1`, or its colour cameras' `P2`/`P3`; Karlsruhe's `P1_roi`/`P2_roi`), read in
//! full.
//!
//! A row is `P = λ K [I | t]`: `K` the shared camera matrix (`fx`, `fy`, `cx`, `cy`, no
//! skew), `t` the offset of the camera from the rig's reference, metres, in the rectified
//! frame, and `λ` any scale (a file may give a multiple of the matrix; `P[2][2]` is `λ`).
//! Each camera's `t = K⁻¹ P[:, 3] / λ` comes from all three rows of its last column, and
//! the baseline is the difference of the two cameras' offsets: KITTI's grey `P0` has
//! `t = 0` and `P1[0][3] = -fx b`, but its colour `P2` and `P3` both carry offsets (and
//! small second- and third-row terms), and reading only the right row's `Tx` made the
//! colour rig's baseline 11 % short. What the rectified model cannot represent is refused:
//! a skew, a rotated camera (entries below the diagonal of the 3x3 part), intrinsics
//! that differ between the two rows, a baseline that is not along `+x` within
//! [`MAX_OFF_AXIS`] of its length.

use std::path::Path;

use nalgebra::Vector3;

use crate::RectifiedStereo;
use crate::error::DatasetError;
use crate::text::{check_baseline, check_same_intrinsics, numbers, parse_error};

/// The largest part of a baseline off the image rows' axis (vertical and along the
/// optical axis together), as a fraction of its length: 1 % tilts the rows of the two
/// images apart by 1 % of each point's disparity (1.6 px at the matcher's largest
/// disparity of 160 px, beyond its row tolerance of 1 px). KITTI's colour pair `P2`/`P3`
/// has 0.63 %.
pub const MAX_OFF_AXIS: f64 = 0.01;

/// Above this fraction the off-axis part is reported in the sequence's notes.
const NOTE_OFF_AXIS: f64 = 1e-3;

/// One projection row of a calibration file: its name, 1-based line and 12 numbers
/// (row-major 3x4).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Row<'a> {
    pub name: &'a str,
    pub line: usize,
    pub p: &'a [f64],
}

/// Entries of a row-major 3x4 matrix, for messages: `P0[2][1]`.
fn entry(name: &str, k: usize) -> String {
    format!("{name}[{}][{}]", k / 4, k % 4)
}

/// The row divided by its scale `P[2][2]`, checked to be `K [I | t]` with `K` upper
/// triangular without skew and positive focal lengths.
fn normalised(path: &Path, row: Row<'_>) -> Result<[f64; 12], DatasetError> {
    let scale = row.p[10];
    if scale == 0.0 {
        return Err(parse_error(
            path,
            row.line,
            format!(
                "{} = 0: the third row of a camera matrix is (0, 0, 1) up to a scale",
                entry(row.name, 10)
            ),
        ));
    }
    let mut q = [0.0; 12];
    for (q, p) in q.iter_mut().zip(row.p) {
        *q = p / scale;
    }
    if !(q[0] > 0.0 && q[5] > 0.0) {
        return Err(parse_error(
            path,
            row.line,
            format!(
                "{} focal lengths must be positive (fx = {}, fy = {})",
                row.name, q[0], q[5]
            ),
        ));
    }
    let tolerance = 1e-6 * q[0].max(q[5]);
    let off = |k: usize| (q[k].abs() > tolerance).then_some(k);
    if let Some(k) = off(1) {
        return Err(parse_error(
            path,
            row.line,
            format!(
                "{} = {} is a skew: the rectified model has none (a rectified camera matrix \
                 has 0 there)",
                entry(row.name, k),
                row.p[k]
            ),
        ));
    }
    if let Some(k) = off(4).or_else(|| off(8)).or_else(|| off(9)) {
        return Err(parse_error(
            path,
            row.line,
            format!(
                "{} = {}: the 3x3 part is not a camera matrix (zeros below its diagonal): a \
                 rotated camera, not a rectified one",
                entry(row.name, k),
                row.p[k]
            ),
        ));
    }
    Ok(q)
}

/// The camera's offset `t = K⁻¹ P[:, 3]`, metres in the rectified frame.
fn offset(q: &[f64; 12]) -> Vector3<f64> {
    let tz = q[11];
    Vector3::new((q[3] - q[2] * tz) / q[0], (q[7] - q[6] * tz) / q[5], tz)
}

/// Where the right camera's centre is from the left one's besides along `x` (`b`: right
/// minus left, y down, z forward), parts under a ten-thousandth of the baseline left out.
fn off_axis_parts(b: &Vector3<f64>) -> String {
    let part = |v: f64, positive: &str, negative: &str| {
        (v.abs() > 1e-4 * b.x).then(|| {
            let side = if v > 0.0 { positive } else { negative };
            format!("{:.4} m {side}", v.abs())
        })
    };
    [part(b.y, "below", "above"), part(b.z, "ahead of", "behind")]
        .into_iter()
        .flatten()
        .collect::<Vec<_>>()
        .join(" and ")
}

/// A calibration file's rectified stereo model, with a note when its baseline is slightly
/// off the rows' axis.
pub type Calibration = (RectifiedStereo, Option<String>);

/// The 12 numbers of a 3x4 projection matrix written as `text`, at `line` of `path`.
///
/// # Errors
/// [`DatasetError::Parse`] naming the file and line: a word that is no number, or a count
/// other than 12.
pub(crate) fn projection_numbers(
    text: &str,
    path: &Path,
    line: usize,
) -> Result<Vec<f64>, DatasetError> {
    let v = numbers(text, path, line)?;
    if v.len() != 12 {
        return Err(parse_error(
            path,
            line,
            format!(
                "a 3x4 projection matrix needs 12 numbers, found {}",
                v.len()
            ),
        ));
    }
    Ok(v)
}

/// The rig of the `left` and `right` rows, with a note when the baseline is off the rows'
/// axis by more than a thousandth (and within [`MAX_OFF_AXIS`]).
///
/// # Errors
/// [`DatasetError::Parse`] naming the file and the line of the row at fault.
pub(crate) fn rectified_pair(
    path: &Path,
    left: Row<'_>,
    right: Row<'_>,
) -> Result<Calibration, DatasetError> {
    let (q0, q1) = (normalised(path, left)?, normalised(path, right)?);
    check_same_intrinsics(path, (left.name, &q0), (right.name, right.line, &q1))?;
    let b = offset(&q0) - offset(&q1);
    let what = if left.p[3] == 0.0 {
        format!("{}[0][3] = {:e}", right.name, right.p[3])
    } else {
        format!(
            "{}[0][3] = {:e} with {}[0][3] = {:e}",
            right.name, right.p[3], left.name, left.p[3]
        )
    };
    if b.x.is_nan() || b.x <= 0.0 {
        return Err(parse_error(
            path,
            right.line,
            format!(
                "{what} gives no positive baseline (expected {}[0][3] - {}[0][3] = fx * b, \
                 the right camera b metres along +x)",
                left.name, right.name
            ),
        ));
    }
    check_baseline(path, right.line, b.x, &what)?;
    let off_axis = b.y.hypot(b.z) / b.x;
    let described = format!(
        "the {} camera is {} the {} camera besides its baseline of {:.4} m ({:.2} % of it)",
        right.name,
        off_axis_parts(&b),
        left.name,
        b.x,
        100.0 * off_axis
    );
    if off_axis > MAX_OFF_AXIS {
        return Err(parse_error(
            path,
            right.line,
            format!(
                "{described}: a pair whose rows are rectified has its baseline along x (at \
                 most {} % off)",
                100.0 * MAX_OFF_AXIS
            ),
        ));
    }
    let note = (off_axis > NOTE_OFF_AXIS).then(|| {
        format!(
            "{}:{}: {described}: read as a baseline along x (the rows drift apart by that \
             fraction of the disparity)",
            path.display(),
            right.line
        )
    });
    let rig = RectifiedStereo {
        fx: q0[0],
        fy: q0[5],
        cx: q0[2],
        cy: q0[6],
        baseline_m: b.x,
    };
    Ok((rig, note))
}

#[cfg(test)]
#[allow(clippy::unwrap_used)]
mod tests {
    use super::*;

    /// KITTI 00-02's colour rows `P2`, `P3` (calib.txt of the odometry benchmark).
    const P2: [f64; 12] = [
        718.856,
        0.0,
        607.1928,
        45.38225,
        0.0,
        718.856,
        185.2157,
        -0.1130887,
        0.0,
        0.0,
        1.0,
        0.003779761,
    ];
    const P3: [f64; 12] = [
        718.856,
        0.0,
        607.1928,
        -337.2877,
        0.0,
        718.856,
        185.2157,
        2.369057,
        0.0,
        0.0,
        1.0,
        0.004915215,
    ];

    fn pair(p0: &[f64], p1: &[f64]) -> Result<(RectifiedStereo, Option<String>), DatasetError> {
        let row = |name, line, p| Row { name, line, p };
        rectified_pair(Path::new("calib.txt"), row("P2", 3, p0), row("P3", 4, p1))
    }

    #[test]
    fn kitti_colour_rows_give_their_own_baseline() {
        let (rig, note) = pair(&P2, &P3).unwrap();
        // t2 - t3 along x: (45.38225 - 607.1928 * 0.003779761 + 337.2877 + 607.1928 *
        // 0.004915215) / 718.856 = 0.53329 m; the right row's Tx alone gave 0.4692 m.
        assert!((rig.baseline_m - 0.533_29).abs() < 1e-5, "{rig:?}");
        let note = note.unwrap();
        assert!(note.contains("0.63 %"), "{note}");
        // A multiple of the rows is the same rig.
        let scaled: Vec<f64> = P3.iter().map(|v| v * -2.5).collect();
        assert_eq!(pair(&P2, &scaled).unwrap().0, rig);
    }

    #[test]
    fn what_the_model_cannot_represent_is_refused() {
        let refused = |k: usize, v: f64, needle: &str| {
            let mut p = P3;
            p[k] = v;
            let e = pair(&P2, &p).unwrap_err().to_string();
            assert!(e.contains(needle), "{k}: {e}");
            assert!(e.starts_with("calib.txt:4: "), "{e}");
        };
        refused(1, 3.0, "P3[0][1] = 3 is a skew");
        refused(
            9,
            0.01,
            "P3[2][1] = 0.01: the 3x3 part is not a camera matrix",
        );
        refused(10, 0.0, "P3[2][2] = 0");
        refused(7, 50.0, "the P3 camera is 0.0694 m above");
        refused(11, 0.2, "m behind the P2 camera");
        refused(3, 100.0, "gives no positive baseline");
        refused(2, 600.0, "P3 cx = 600 differs from P2 cx = 607.1928");
    }
}
