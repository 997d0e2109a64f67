//! The KITTI odometry devkit's segment errors (`evaluate_odometry.cpp` of the KITTI
//! odometry benchmark), the figures VO papers report: translation error in percent and
//! rotation error in degrees per 100 m, over every sub-sequence of 100, 200, ..., 800 m.
//!
//! As the devkit: the distance along the ground truth is accumulated frame by frame
//! (`trajectoryDistances`); a segment of length `L` starts at every 10th frame `i`
//! (`step_size = 10`) and ends at the first frame `j >= i` whose distance exceeds
//! `dist[i] + L` (`lastFrameFromSegmentLength`; no segment when there is none); its
//! error pose is `E = (P_i^-1 P_j)^-1 (Q_i^-1 Q_j)` with `P` the estimate and `Q` the
//! ground truth, its translation error `|t(E)| / L` (a ratio, reported in percent) and its
//! rotation error `acos(clamp((trace R(E) - 1) / 2, -1, 1)) / L` (radians per metre,
//! reported in degrees per 100 m). The averages are over all segments of one length, and
//! over all segments of every length (each segment weighs the same), as the devkit's
//! `saveErrorPlots` and `saveStats`.
//!
//! Two differences from the devkit, both below 1e-6 of the reported figures on KITTI 00
//! (`tools/kitti_segments/README.md`): distances and errors are computed in double
//! precision (the devkit accumulates distances in `float`), and the rotations are those
//! the trajectory readers give (the nearest rotation to each file's 3x3 block).
//!
//! A short clip has no 100 m segment: `scale` multiplies every length (0.1 gives
//! 10-80 m); the result says so, and such figures are not comparable with the KITTI table.

use nalgebra::Isometry3;
use serde::Serialize;

use crate::error::EvalError;

/// The KITTI devkit's segment lengths, metres.
pub const KITTI_LENGTHS_M: [f64; 8] = [100.0, 200.0, 300.0, 400.0, 500.0, 600.0, 700.0, 800.0];
/// The devkit's step between segment starts, frames.
pub const KITTI_STEP_FRAMES: usize = 10;

/// The error of one segment.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Segment {
    /// Its first frame.
    pub first_frame: usize,
    /// Its last frame: the first whose ground-truth distance exceeds the first's plus the length.
    pub last_frame: usize,
    /// The segment length (nominal, as the devkit divides by it), metres.
    pub length_m: f64,
    /// Translation error, percent of the length.
    pub translation_percent: f64,
    /// Rotation error, degrees per 100 m.
    pub rotation_deg_per_100m: f64,
}

/// The mean errors of the segments of one length.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct SegmentLength {
    /// Segment length, metres.
    pub length_m: f64,
    /// Number of segments.
    pub n: usize,
    /// Mean translation error, percent.
    pub translation_percent: f64,
    /// Mean rotation error, degrees per 100 m.
    pub rotation_deg_per_100m: f64,
}

/// The KITTI devkit's segment errors.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct KittiSegments {
    /// How they were computed, or why there are none.
    pub note: String,
    /// The factor applied to the devkit's lengths (1: the KITTI figures).
    pub scale: f64,
    /// Mean translation error over all segments, percent.
    pub translation_percent: Option<f64>,
    /// Mean rotation error over all segments, degrees per 100 m.
    pub rotation_deg_per_100m: Option<f64>,
    /// Per length with at least one segment, shortest first.
    pub per_length: Vec<SegmentLength>,
    /// Every segment, by length then first frame.
    pub segments: Vec<Segment>,
}

/// Distance along `poses` from the first, metres, per frame (the devkit's `trajectoryDistances`).
fn distances(poses: &[Isometry3<f64>]) -> Vec<f64> {
    let mut dist = Vec::with_capacity(poses.len());
    let mut total = 0.0;
    for (i, p) in poses.iter().enumerate() {
        if i > 0 {
            total += (p.translation.vector - poses[i - 1].translation.vector).norm();
        }
        dist.push(total);
    }
    dist
}

/// The error of the segment from `first` to `last` of nominal length `len` metres.
fn segment_error(
    estimate: &[Isometry3<f64>],
    ground_truth: &[Isometry3<f64>],
    (first, last): (usize, usize),
    len: f64,
) -> Segment {
    let dg = ground_truth[first].inverse() * ground_truth[last];
    let de = estimate[first].inverse() * estimate[last];
    let err = de.inverse() * dg;
    let r = err.rotation.to_rotation_matrix().into_inner();
    let angle = ((r.trace() - 1.0) / 2.0).clamp(-1.0, 1.0).acos();
    Segment {
        first_frame: first,
        last_frame: last,
        length_m: len,
        translation_percent: 100.0 * err.translation.vector.norm() / len,
        rotation_deg_per_100m: 100.0 * angle.to_degrees() / len,
    }
}

fn mean<'a>(values: impl Iterator<Item = &'a Segment>, f: fn(&Segment) -> f64) -> (f64, usize) {
    let (sum, n) = values.fold((0.0, 0usize), |(s, n), seg| (s + f(seg), n + 1));
    (sum / n.max(1) as f64, n)
}

/// The KITTI devkit's segment errors of `estimate` against `ground_truth` (paired by
/// index), with every length multiplied by `scale` (1 for the KITTI figures).
///
/// # Errors
/// [`EvalError::SegmentScale`] unless `scale` is finite and in (0, 1];
/// [`EvalError::LengthMismatch`] for trajectories of different lengths.
pub fn kitti_segments(
    estimate: &[Isometry3<f64>],
    ground_truth: &[Isometry3<f64>],
    scale: f64,
) -> Result<KittiSegments, EvalError> {
    if !(scale.is_finite() && scale > 0.0 && scale <= 1.0) {
        return Err(EvalError::SegmentScale { scale });
    }
    if estimate.len() != ground_truth.len() {
        return Err(EvalError::LengthMismatch {
            estimate: "the estimate".into(),
            n_estimate: estimate.len(),
            ground_truth: "the ground truth".into(),
            n_ground_truth: ground_truth.len(),
        });
    }
    let dist = distances(ground_truth);
    let mut segments = Vec::new();
    for len in KITTI_LENGTHS_M.map(|l| l * scale) {
        for first in (0..dist.len()).step_by(KITTI_STEP_FRAMES) {
            if let Some(last) = (first..dist.len()).find(|&i| dist[i] > dist[first] + len) {
                segments.push(segment_error(estimate, ground_truth, (first, last), len));
            }
        }
    }
    let per_length: Vec<SegmentLength> = KITTI_LENGTHS_M
        .map(|l| l * scale)
        .into_iter()
        .filter_map(|len| {
            let of_len = || segments.iter().filter(move |s| s.length_m == len);
            let (t, n) = mean(of_len(), |s| s.translation_percent);
            let (r, _) = mean(of_len(), |s| s.rotation_deg_per_100m);
            (n > 0).then_some(SegmentLength {
                length_m: len,
                n,
                translation_percent: t,
                rotation_deg_per_100m: r,
            })
        })
        .collect();
    let lengths = format!("{:.0}-{:.0} m", 100.0 * scale, 800.0 * scale);
    let scaled = if scale == 1.0 {
        String::new()
    } else {
        format!(" (the KITTI lengths x {scale}: not comparable with the KITTI benchmark's figures)")
    };
    let total = dist.last().copied().unwrap_or(0.0);
    if segments.is_empty() {
        return Ok(KittiSegments {
            note: format!(
                "not available: the path is {total:.1} m long, the shortest segment is {:.0} m{scaled}",
                100.0 * scale
            ),
            scale,
            translation_percent: None,
            rotation_deg_per_100m: None,
            per_length,
            segments,
        });
    }
    let (t, n) = mean(segments.iter(), |s| s.translation_percent);
    let (r, _) = mean(segments.iter(), |s| s.rotation_deg_per_100m);
    Ok(KittiSegments {
        note: format!(
            "KITTI devkit: {n} segments of {lengths} starting every {KITTI_STEP_FRAMES} frames{scaled}"
        ),
        scale,
        translation_percent: Some(t),
        rotation_deg_per_100m: Some(r),
        per_length,
        segments,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    /// A straight line along z, `step` metres per frame.
    fn line(n: usize, step: f64) -> Vec<Isometry3<f64>> {
        (0..n)
            .map(|i| Isometry3::translation(0.0, 0.0, step * i as f64))
            .collect()
    }

    #[test]
    fn a_long_line_one_percent_too_long() {
        // 300 frames, 1 m each; the estimate 1 % too long: no rotation error.
        let k = kitti_segments(&line(300, 1.01), &line(300, 1.0), 1.0).expect("segments");
        let t = k.translation_percent.expect("long enough");
        // A segment "longer than L" ends at L+1 frames: error 1 % of (L+1)/L.
        assert!(
            (k.per_length[0].translation_percent - 1.01).abs() < 1e-9,
            "{t}"
        );
        assert!((k.per_length[1].translation_percent - 1.005).abs() < 1e-9);
        assert_eq!(k.rotation_deg_per_100m, Some(0.0));
        assert_eq!(k.per_length[0].length_m, 100.0);
        assert_eq!(k.per_length[0].n, 20); // starts 0, 10, ..., 190 (end <= 299)
        assert_eq!(k.per_length[1].n, 10); // starts 0, ..., 90 (end 201..=291)
        assert_eq!(k.per_length.len(), 2);
        assert_eq!(k.segments.len(), 30);
        assert!((t - (20.0 * 1.01 + 10.0 * 1.005) / 30.0).abs() < 1e-9);
        assert_eq!(
            (k.segments[0].first_frame, k.segments[0].last_frame),
            (0, 101)
        );
    }

    #[test]
    fn a_steady_turn_in_degrees_per_100m() {
        // The ground truth goes straight, the estimate turns 0.01 degree a frame (1 m)
        // about the vertical axis: 101 frames of a 100 m segment turn 1.01 degrees.
        let gt = line(120, 1.0);
        let est: Vec<_> = (0..120)
            .map(|i| {
                let a = (0.01 * i as f64).to_radians();
                Isometry3::new(Vector3::new(0.0, 0.0, i as f64), Vector3::new(0.0, a, 0.0))
            })
            .collect();
        let k = kitti_segments(&est, &gt, 1.0).expect("segments");
        assert!((k.rotation_deg_per_100m.expect("r") - 1.01).abs() < 1e-6);
    }

    #[test]
    fn a_short_clip_with_scaled_lengths() {
        // 52 m: no KITTI segment; at a tenth, 10-50 m segments, and the note says so.
        let (gt, est) = (line(53, 1.0), line(53, 1.02));
        let k = kitti_segments(&est, &gt, 1.0).expect("segments");
        assert!(k.translation_percent.is_none() && k.segments.is_empty());
        assert!(k.note.contains("52.0 m"), "{}", k.note);
        let k = kitti_segments(&est, &gt, 0.1).expect("segments");
        assert_eq!(k.per_length.len(), 5);
        assert!(k.note.contains("not comparable"), "{}", k.note);
        assert!((k.per_length[0].translation_percent - 2.2).abs() < 1e-9);
    }

    #[test]
    fn bad_scale_and_lengths_are_refused() {
        for scale in [0.0, -1.0, 1.5, f64::NAN, f64::INFINITY] {
            let e = kitti_segments(&line(3, 1.0), &line(3, 1.0), scale).expect_err("scale");
            assert!(e.to_string().contains("scale"), "{e}");
        }
        let e = kitti_segments(&line(3, 1.0), &line(4, 1.0), 1.0).expect_err("lengths");
        assert!(e.to_string().contains("3 poses"), "{e}");
    }
}
