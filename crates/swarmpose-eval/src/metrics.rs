//! Odometry metrics on associated poses ([`Associated`]).
//!
//! * **Eq. (20), per frame**: for every consecutive pair of frames `(k-1, k)` the paper's
//!   rotation error `||I - R_gt R_est^T||_F` between the *relative* rotations
//!   `R_gt = R_gt,k-1^T R_gt,k` and `R_est = R_est,k-1^T R_est,k`: the rotation each
//!   pair of images yields, as Table I compares per-image orientations of the
//!   estimators with the IMU's. Its RMS over the pairs is our Table I number. The
//!   same error between the absolute orientations (both trajectories re-based to their
//!   first pose) is reported beside it.
//! * **ATE** (absolute trajectory error, evo's `evo_ape` translation part): the
//!   distance between the estimated and true positions of each frame, raw (no
//!   alignment) and after the SE(3) alignment of Umeyama (no scale) of the estimate
//!   onto the ground truth (`evo_ape -a`).
//! * **RPE** (relative pose error, `evo_rpe --delta 1 --delta_unit f`): per consecutive
//!   pair `E = (Q_k-1^-1 Q_k)^-1 (P_k-1^-1 P_k)` with `Q` the ground truth and `P` the
//!   estimate; its translation norm (metres) and rotation angle (degrees).
//! * **Final drift**: the distance between the last estimated and true positions once
//!   the estimate is re-based on the ground truth's first pose, as a percentage of the
//!   ground-truth path length.
//! * **KITTI segment errors** (the KITTI odometry devkit, [`crate::segments`]): for
//!   segments of 100, 200, ..., 800 m starting every 10 frames, the relative pose error
//!   over the segment divided by its length; only available when the path is at least
//!   100 m long (or the lengths are scaled down).
//!
//! Statistics follow evo: RMSE, mean, median, population standard deviation, min, max,
//! sum of squares.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use serde::Serialize;
use swarmpose_core::geometry::{frobenius_rotation_error, quaternion_wxyz};

use crate::associate::Associated;
use crate::error::EvalError;
use crate::segments::{KittiSegments, kitti_segments};

/// Summary statistics of per-frame errors, as evo prints them.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Stats {
    /// Number of values.
    pub n: usize,
    /// Root mean square.
    pub rmse: f64,
    /// Mean.
    pub mean: f64,
    /// Median (mean of the middle two for an even count).
    pub median: f64,
    /// Population standard deviation.
    pub std: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Sum of squares.
    pub sse: f64,
}

impl Stats {
    /// Statistics of `values` (all zero for an empty slice).
    #[must_use]
    pub fn of(values: &[f64]) -> Self {
        let n = values.len();
        if n == 0 {
            return Self {
                n,
                rmse: 0.0,
                mean: 0.0,
                median: 0.0,
                std: 0.0,
                min: 0.0,
                max: 0.0,
                sse: 0.0,
            };
        }
        let nf = n as f64;
        let sse: f64 = values.iter().map(|v| v * v).sum();
        let mean = values.iter().sum::<f64>() / nf;
        let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / nf;
        let mut sorted = values.to_vec();
        sorted.sort_by(f64::total_cmp);
        let median = if n % 2 == 1 {
            sorted[n / 2]
        } else {
            0.5 * (sorted[n / 2 - 1] + sorted[n / 2])
        };
        Self {
            n,
            rmse: (sse / nf).sqrt(),
            mean,
            median,
            std: var.sqrt(),
            min: sorted[0],
            max: sorted[n - 1],
            sse,
        }
    }
}

/// A rigid alignment `y = R x + t`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Alignment {
    /// Rotation `[w, x, y, z]`.
    pub rotation_wxyz: [f64; 4],
    /// Translation, metres.
    pub translation: [f64; 3],
}

/// Umeyama's least-squares rigid alignment without scale (Umeyama 1991, eq. 39-42 with
/// `c = 1`): the `R, t` minimising `Σ |y_i - (R x_i + t)|²`.
///
/// # Errors
/// [`EvalError::TooFew`] for fewer than 2 points or unequal lengths.
pub fn umeyama(x: &[Point3<f64>], y: &[Point3<f64>]) -> Result<Isometry3<f64>, EvalError> {
    if x.len() != y.len() || x.len() < 2 {
        return Err(EvalError::TooFew {
            what: "points to align".into(),
            got: x.len().min(y.len()),
            needed: 2,
        });
    }
    let n = x.len() as f64;
    let mx = x.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n;
    let my = y.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n;
    let mut sigma = Matrix3::zeros();
    for (a, b) in x.iter().zip(y) {
        sigma += (b.coords - my) * (a.coords - mx).transpose();
    }
    sigma /= n;
    let svd = sigma.try_svd(true, true, 1e-15, 10_000);
    let Some((Some(u), Some(v_t))) = svd.map(|s| (s.u, s.v_t)) else {
        return Err(EvalError::TooFew {
            what: "points to align (SVD failed)".into(),
            got: x.len(),
            needed: 3,
        });
    };
    let mut s = Matrix3::identity();
    if u.determinant() * v_t.determinant() < 0.0 {
        s[(2, 2)] = -1.0;
    }
    let r = u * s * v_t;
    let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let t = my - rot * mx;
    Ok(Isometry3::from_parts(Translation3::from(t), rot))
}

/// Everything `swarmpose evaluate` reports.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// Pairs of associated poses.
    pub n_pairs: usize,
    /// Ground-truth path length over the pairs, metres.
    pub path_length_m: f64,
    /// Eq. (20) per consecutive pair of frames (relative rotations); `n_pairs - 1` values.
    pub eq20_per_frame: Vec<f64>,
    /// Their RMS: our Table I.
    pub eq20_rms: f64,
    /// Eq. (20) between absolute orientations (both re-based to their first pose), RMS.
    pub eq20_absolute_rms: f64,
    /// ATE without alignment, metres (per frame: `ate_raw_per_frame`).
    pub ate_raw: Stats,
    /// ATE per frame without alignment, metres.
    pub ate_raw_per_frame: Vec<f64>,
    /// ATE after the SE(3) Umeyama alignment, metres.
    pub ate_aligned: Stats,
    /// ATE per frame after alignment, metres.
    pub ate_aligned_per_frame: Vec<f64>,
    /// The alignment applied to the estimate.
    pub alignment: Alignment,
    /// RPE translation per consecutive pair, metres.
    pub rpe_translation: Stats,
    /// Per pair, metres.
    pub rpe_translation_per_frame: Vec<f64>,
    /// RPE rotation per consecutive pair, degrees.
    pub rpe_rotation_deg: Stats,
    /// Per pair, degrees.
    pub rpe_rotation_deg_per_frame: Vec<f64>,
    /// Final position error after re-basing on the first pose, metres.
    pub final_drift_m: f64,
    /// The same as a percentage of the path length (`None` for a path shorter than 10 cm, where a
    /// percentage means nothing).
    pub final_drift_percent: Option<f64>,
    /// KITTI devkit segment errors.
    pub kitti: KittiSegments,
}

/// Eq. (20) between the relative rotations of consecutive frames: `n - 1` values.
#[must_use]
pub fn eq20_relative(estimate: &[Isometry3<f64>], ground_truth: &[Isometry3<f64>]) -> Vec<f64> {
    estimate
        .windows(2)
        .zip(ground_truth.windows(2))
        .map(|(e, g)| {
            let re = e[0].rotation.inverse() * e[1].rotation;
            let rg = g[0].rotation.inverse() * g[1].rotation;
            frobenius_rotation_error(&rg, &re)
        })
        .collect()
}

/// Root mean square of `v` (0 for none).
#[must_use]
pub fn rms(v: &[f64]) -> f64 {
    Stats::of(v).rmse
}

/// Length of the path through the positions of `poses`, metres.
#[must_use]
pub fn path_length(poses: &[Isometry3<f64>]) -> f64 {
    poses
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum()
}

/// `estimate` re-based so that its first pose equals `ground_truth[0]`.
#[must_use]
pub fn rebase(estimate: &[Isometry3<f64>], first: &Isometry3<f64>) -> Vec<Isometry3<f64>> {
    let Some(e0) = estimate.first() else {
        return Vec::new();
    };
    let t = first * e0.inverse();
    estimate.iter().map(|e| t * e).collect()
}

/// RPE with a delta of one frame: (translation metres, rotation degrees) per pair.
#[must_use]
pub fn rpe(estimate: &[Isometry3<f64>], ground_truth: &[Isometry3<f64>]) -> (Vec<f64>, Vec<f64>) {
    estimate
        .windows(2)
        .zip(ground_truth.windows(2))
        .map(|(p, q)| {
            let e = (q[0].inverse() * q[1]).inverse() * (p[0].inverse() * p[1]);
            (e.translation.vector.norm(), e.rotation.angle().to_degrees())
        })
        .unzip()
}

/// Every metric of `pairs` (the KITTI segments at the devkit's lengths).
///
/// # Errors
/// [`EvalError::TooFew`] for fewer than 2 pairs.
pub fn evaluate(pairs: &Associated) -> Result<Evaluation, EvalError> {
    evaluate_with(pairs, 1.0)
}

/// Every metric of `pairs`, the KITTI segment lengths multiplied by `segment_scale`.
///
/// # Errors
/// [`EvalError::TooFew`] for fewer than 2 pairs; [`EvalError::SegmentScale`] unless
/// `segment_scale` is in (0, 1].
pub fn evaluate_with(pairs: &Associated, segment_scale: f64) -> Result<Evaluation, EvalError> {
    let n = pairs.len();
    if n < 2 {
        return Err(EvalError::TooFew {
            what: "associated poses".into(),
            got: n,
            needed: 2,
        });
    }
    let (est, gt) = (&pairs.estimate, &pairs.ground_truth);
    let eq20 = eq20_relative(est, gt);
    let rebased = rebase(est, &gt[0]);
    let abs: Vec<f64> = rebased
        .iter()
        .zip(gt)
        .map(|(e, g)| frobenius_rotation_error(&g.rotation, &e.rotation))
        .collect();
    let dist = |a: &Isometry3<f64>, b: &Isometry3<f64>| {
        (a.translation.vector - b.translation.vector).norm()
    };
    let ate_raw: Vec<f64> = est.iter().zip(gt).map(|(e, g)| dist(e, g)).collect();
    let x: Vec<Point3<f64>> = est
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    let y: Vec<Point3<f64>> = gt
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    let align = umeyama(&x, &y)?;
    let ate_aligned: Vec<f64> = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (b - align * a).norm())
        .collect();
    let (rpe_t, rpe_r) = rpe(est, gt);
    let length = path_length(gt);
    let drift = dist(&rebased[n - 1], &gt[n - 1]);
    Ok(Evaluation {
        n_pairs: n,
        path_length_m: length,
        eq20_rms: rms(&eq20),
        eq20_per_frame: eq20,
        eq20_absolute_rms: rms(&abs),
        ate_raw: Stats::of(&ate_raw),
        ate_raw_per_frame: ate_raw,
        ate_aligned: Stats::of(&ate_aligned),
        ate_aligned_per_frame: ate_aligned,
        alignment: Alignment {
            rotation_wxyz: quaternion_wxyz(&align.rotation),
            translation: align.translation.vector.into(),
        },
        rpe_translation: Stats::of(&rpe_t),
        rpe_translation_per_frame: rpe_t,
        rpe_rotation_deg: Stats::of(&rpe_r),
        rpe_rotation_deg_per_frame: rpe_r,
        final_drift_m: drift,
        final_drift_percent: (length >= 0.1).then(|| 100.0 * drift / length),
        kitti: kitti_segments(est, gt, segment_scale)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::associate::Associated;

    fn pairs(est: Vec<Isometry3<f64>>, gt: Vec<Isometry3<f64>>) -> Associated {
        Associated {
            stamps: (0..est.len()).map(|i| i as f64).collect(),
            estimate: est,
            ground_truth: gt,
        }
    }

    /// A straight line along z, 1 m per frame.
    fn line(n: usize) -> Vec<Isometry3<f64>> {
        (0..n)
            .map(|i| Isometry3::translation(0.0, 0.0, i as f64))
            .collect()
    }

    #[test]
    fn stats_like_numpy() {
        let s = Stats::of(&[1.0, 2.0, 3.0, 4.0]);
        assert_eq!(s.median, 2.5);
        assert_eq!(s.mean, 2.5);
        assert!((s.rmse - 7.5f64.sqrt()).abs() < 1e-15);
        assert!((s.std - 1.25f64.sqrt()).abs() < 1e-15);
        assert_eq!((s.min, s.max, s.sse), (1.0, 4.0, 30.0));
        assert_eq!(Stats::of(&[3.0, 1.0, 2.0]).median, 2.0);
    }

    #[test]
    fn identical_trajectories_have_no_error() {
        let gt: Vec<_> = (0..20)
            .map(|i| {
                let f = i as f64;
                Isometry3::new(
                    Vector3::new(f.sin(), 0.1 * f, f),
                    Vector3::new(0.0, 0.05 * f, 0.0),
                )
            })
            .collect();
        let e = evaluate(&pairs(gt.clone(), gt)).expect("eval");
        assert!(e.eq20_rms < 1e-12 && e.ate_raw.max < 1e-12 && e.ate_aligned.max < 1e-9);
        assert!(e.rpe_translation.max < 1e-12 && e.rpe_rotation_deg.max < 1e-9);
        assert!(e.final_drift_m < 1e-12);
        assert_eq!(e.eq20_per_frame.len(), 19);
    }

    #[test]
    fn scaled_line_drift_and_rpe() {
        // Estimate 2 % too long per step: 10 frames, 9 m path, final error 0.18 m.
        let gt = line(10);
        let est: Vec<_> = (0..10)
            .map(|i| Isometry3::translation(0.0, 0.0, 1.02 * i as f64))
            .collect();
        let e = evaluate(&pairs(est, gt)).expect("eval");
        assert!((e.path_length_m - 9.0).abs() < 1e-12);
        assert!((e.final_drift_m - 0.18).abs() < 1e-12);
        assert!((e.final_drift_percent.expect("long") - 2.0).abs() < 1e-9);
        assert!((e.rpe_translation.rmse - 0.02).abs() < 1e-12);
        assert!((e.rpe_translation.median - 0.02).abs() < 1e-12);
        assert!(e.rpe_rotation_deg.max < 1e-12 && e.eq20_rms < 1e-15);
        // Raw ATE: 0.02 i; aligned: the best shift leaves 0.02 (i - 4.5).
        assert!((e.ate_raw.max - 0.18).abs() < 1e-12);
        let want: f64 = ((0..10)
            .map(|i| (0.02 * (i as f64 - 4.5)).powi(2))
            .sum::<f64>()
            / 10.0)
            .sqrt();
        assert!(
            (e.ate_aligned.rmse - want).abs() < 1e-12,
            "{} vs {want}",
            e.ate_aligned.rmse
        );
        assert!(e.kitti.translation_percent.is_none());
        assert!(e.kitti.note.contains("9.0 m"), "{}", e.kitti.note);
    }

    #[test]
    fn umeyama_recovers_a_rigid_motion() {
        let t = Isometry3::new(Vector3::new(1.0, -2.0, 3.0), Vector3::new(0.2, -0.4, 0.9));
        let x: Vec<Point3<f64>> = (0..12)
            .map(|i| {
                let f = i as f64;
                Point3::new(f.cos() * 3.0, f * 0.5, (2.0 * f).sin())
            })
            .collect();
        let y: Vec<_> = x.iter().map(|p| t * p).collect();
        let a = umeyama(&x, &y).expect("align");
        assert!((a.to_homogeneous() - t.to_homogeneous()).norm() < 1e-10);
        // Raw ATE of a rotated copy is large; aligned, zero.
        let gt: Vec<_> = y
            .iter()
            .map(|p| Isometry3::translation(p.x, p.y, p.z))
            .collect();
        let est: Vec<_> = x
            .iter()
            .map(|p| Isometry3::translation(p.x, p.y, p.z))
            .collect();
        let e = evaluate(&pairs(est, gt)).expect("eval");
        assert!(e.ate_raw.rmse > 1.0 && e.ate_aligned.rmse < 1e-10);
    }

    #[test]
    fn eq20_compares_relative_rotations() {
        // Ground truth turns 0.1 rad per frame about y; the estimate 0.11 rad: every
        // per-frame error is that of a 0.01 rad rotation, 2 sqrt(2) sin(0.005).
        let gt: Vec<_> = (0..6)
            .map(|i| Isometry3::rotation(Vector3::new(0.0, 0.1 * i as f64, 0.0)))
            .collect();
        let est: Vec<_> = (0..6)
            .map(|i| Isometry3::rotation(Vector3::new(0.0, 0.11 * i as f64, 0.0)))
            .collect();
        let e = evaluate(&pairs(est, gt)).expect("eval");
        let want = 2.0 * 2f64.sqrt() * 0.005f64.sin();
        assert!(e.eq20_per_frame.iter().all(|v| (v - want).abs() < 1e-12));
        assert!((e.eq20_rms - want).abs() < 1e-12);
        assert!((e.rpe_rotation_deg.mean - 0.01f64.to_degrees()).abs() < 1e-9);
        // The absolute error grows to 0.05 rad at the last frame.
        assert!(e.eq20_absolute_rms > want);
    }

    #[test]
    fn too_few_pairs() {
        let e = evaluate(&pairs(line(1), line(1))).expect_err("one pose");
        assert!(e.to_string().contains("1 pose"), "{e}");
    }
}
