//! Self-calibration of the disparity offset from image data alone.
//!
//! A horizontal principal point of the right camera that is off in the calibration
//! shifts every disparity by the same `δ` pixels: a point of measured disparity `d` is
//! really at `p d / (d + δ)`. Far points (small `d`) move most, so a wrong `δ` bends the
//! scene non-rigidly and the motion between two frames no longer fits all depths at once.
//! The offset is therefore the one that makes the moving pairs most rigid: for each
//! candidate `δ`, each pair's motion is refined on the corrected points
//! ([`super::refine_stereo`]) and the robust Mahalanobis cost of all correspondences
//! (squared Mahalanobis residuals truncated at the χ²(3) 99 % gate, covariances rescaled
//! with the points so that shrinking the scene does not lower the cost) is summed. No
//! ground truth is used. A pure translation-free pair says nothing about `δ`.
//!
//! [`calibrate_correction`] fits the two-parameter correction of [`DisparityCorrection`]
//! (constant plus a term quadratic in the image column, the signature of a yaw of the
//! right camera) by the same cost, with a Nelder-Mead search started from the constant
//! offset.

use nalgebra::Isometry3;
use swarmpose_core::Estimator;

use super::{CHI2_3_99, DisparityCorrection, FrameMatches, refine_stereo};

/// Smallest translation, metres, for a pair to take part in the calibration.
pub const MIN_CALIBRATION_TRANSLATION_M: f64 = 0.2;

/// Pairs used to calibrate the disparity offset (evenly spread over the moving ones).
pub const CALIBRATION_PAIRS: usize = 8;
/// Offsets searched, pixels.
pub const OFFSET_RANGE_PX: (f64, f64) = (-3.0, 5.0);

/// Robust Mahalanobis cost of the pairs with the disparity correction `delta` applied: per
/// pair the motion refined on the corrected points from `start`, then the sum over
/// every correspondence of its squared Mahalanobis residual, truncated at the 99 %
/// gate. The covariances are rescaled with the points, so a uniform shrinking of the
/// scene does not lower the cost.
fn correction_cost(pairs: &[(&FrameMatches, Isometry3<f64>)], delta: DisparityCorrection) -> f64 {
    let mut total = 0.0;
    for (m, start) in pairs {
        let Ok(c) = m.with_disparity_correction(delta) else {
            return f64::INFINITY;
        };
        let n = c.correspondences.len();
        let Ok((pose, _)) = refine_stereo(
            &c.correspondences,
            &c.src_covariances,
            &c.dst_covariances,
            start,
            CHI2_3_99,
            5,
        ) else {
            total += n as f64 * CHI2_3_99;
            continue;
        };
        let r = pose.rotation.to_rotation_matrix();
        let data = &c.correspondences;
        for i in 0..n {
            let res = data.dst()[i] - pose * data.src()[i];
            let cov =
                r.matrix() * c.src_covariances[i] * r.matrix().transpose() + c.dst_covariances[i];
            let d2 = cov
                .try_inverse()
                .map_or(CHI2_3_99, |w| (res.transpose() * w * res)[0]);
            total += d2.min(CHI2_3_99);
        }
    }
    total
}

/// The disparity offset that minimises the robust cost of the module documentation over up to
/// [`CALIBRATION_PAIRS`] of `moving`: a grid of 1 px over [`OFFSET_RANGE_PX`], then a
/// golden-section search around the best. 0 for fewer than 3 pairs.
#[must_use]
pub fn calibrate_offset(moving: &[(&FrameMatches, Isometry3<f64>)]) -> f64 {
    if moving.len() < 3 {
        return 0.0;
    }
    let chosen = spread_pairs(moving);
    let cost = |d: f64| correction_cost(&chosen, DisparityCorrection::constant(d));
    let (lo, hi) = OFFSET_RANGE_PX;
    let steps = (hi - lo).round() as usize;
    let grid: Vec<(f64, f64)> = (0..=steps)
        .map(|i| {
            let d = lo + i as f64;
            (d, cost(d))
        })
        .collect();
    let Some(&(best, _)) = grid.iter().min_by(|a, b| a.1.total_cmp(&b.1)) else {
        return 0.0;
    };
    let (mut a, mut b) = ((best - 1.0).max(lo), (best + 1.0).min(hi));
    let g = (5f64.sqrt() - 1.0) / 2.0;
    let (mut x1, mut x2) = (b - g * (b - a), a + g * (b - a));
    let (mut f1, mut f2) = (cost(x1), cost(x2));
    for _ in 0..10 {
        if f1 < f2 {
            b = x2;
            x2 = x1;
            f2 = f1;
            x1 = b - g * (b - a);
            f1 = cost(x1);
        } else {
            a = x1;
            x1 = x2;
            f1 = f2;
            x2 = a + g * (b - a);
            f2 = cost(x2);
        }
    }
    (a + b) / 2.0
}

/// Up to [`CALIBRATION_PAIRS`] of `moving`, evenly spread.
fn spread_pairs<'a>(
    moving: &[(&'a FrameMatches, Isometry3<f64>)],
) -> Vec<(&'a FrameMatches, Isometry3<f64>)> {
    let k = moving.len().min(CALIBRATION_PAIRS);
    (0..k).map(|j| moving[j * moving.len() / k]).collect()
}

/// Largest `|quadratic_px|` searched, pixels (a yaw of about 0.8° at f = 700 px).
pub const QUADRATIC_LIMIT_PX: f64 = 10.0;

/// The [`DisparityCorrection`] that minimises the robust cost of the module documentation
/// over up to [`CALIBRATION_PAIRS`] of `moving`: Nelder-Mead from the constant offset of
/// [`calibrate_offset`], at most 60 iterations, until the simplex is within 0.005 px.
/// No correction for fewer than 3 pairs.
#[must_use]
pub fn calibrate_correction(moving: &[(&FrameMatches, Isometry3<f64>)]) -> DisparityCorrection {
    if moving.len() < 3 {
        return DisparityCorrection::default();
    }
    let a0 = calibrate_offset(moving);
    let chosen = spread_pairs(moving);
    let cost = |v: [f64; 2]| {
        if v[1].abs() > QUADRATIC_LIMIT_PX {
            return f64::INFINITY;
        }
        correction_cost(
            &chosen,
            DisparityCorrection {
                offset_px: v[0],
                quadratic_px: v[1],
            },
        )
    };
    let [a, c] = nelder_mead(cost, [[a0, 0.0], [a0 + 0.5, 0.0], [a0, 1.5]], 60, 0.005);
    DisparityCorrection {
        offset_px: a,
        quadratic_px: c,
    }
}

/// Nelder-Mead minimisation in 2D from the simplex `start` (reflection 1, expansion 2,
/// contraction and shrink 0.5): at most `iterations`, until every vertex is within `tol`
/// of the best in each coordinate.
fn nelder_mead(
    f: impl Fn([f64; 2]) -> f64,
    start: [[f64; 2]; 3],
    iterations: usize,
    tol: f64,
) -> [f64; 2] {
    let mut s: Vec<([f64; 2], f64)> = start.iter().map(|&v| (v, f(v))).collect();
    let along =
        |a: [f64; 2], b: [f64; 2], t: f64| [a[0] + t * (b[0] - a[0]), a[1] + t * (b[1] - a[1])];
    for _ in 0..iterations {
        s.sort_by(|x, y| x.1.total_cmp(&y.1));
        let (best, worst) = (s[0].0, s[2].0);
        if s[1..]
            .iter()
            .all(|(v, _)| (v[0] - best[0]).abs() < tol && (v[1] - best[1]).abs() < tol)
        {
            break;
        }
        let centroid = along(s[0].0, s[1].0, 0.5);
        let reflected = along(centroid, worst, -1.0);
        let fr = f(reflected);
        if fr < s[0].1 {
            let expanded = along(centroid, worst, -2.0);
            let fe = f(expanded);
            s[2] = if fe < fr {
                (expanded, fe)
            } else {
                (reflected, fr)
            };
        } else if fr < s[1].1 {
            s[2] = (reflected, fr);
        } else {
            let contracted = along(centroid, worst, 0.5);
            let fc = f(contracted);
            if fc < s[2].1 {
                s[2] = (contracted, fc);
            } else {
                for vertex in s.iter_mut().skip(1) {
                    let v = along(best, vertex.0, 0.5);
                    *vertex = (v, f(v));
                }
            }
        }
    }
    s.sort_by(|x, y| x.1.total_cmp(&y.1));
    s[0].0
}

/// The pairs of `matches` (consecutive frame pairs) that `estimator` registers with a
/// translation of at least [`MIN_CALIBRATION_TRANSLATION_M`], with their motions.
fn moving_pairs<'a>(
    matches: &'a [FrameMatches],
    estimator: &dyn Estimator,
    seed: u64,
) -> Vec<(&'a FrameMatches, Isometry3<f64>)> {
    matches
        .iter()
        .enumerate()
        .filter_map(|(k, m)| {
            let e = estimator
                .estimate_seeded(&m.correspondences, seed.wrapping_add(k as u64))
                .ok()?;
            (e.transform.translation.vector.norm() >= MIN_CALIBRATION_TRANSLATION_M)
                .then_some((m, e.transform))
        })
        .collect()
}

/// Self-calibrates the disparity offset (pixels) of `matches`, consecutive frame pairs of
/// one sequence: each pair's motion from `estimator` (seeded with `seed + index`), the
/// pairs that move at least [`MIN_CALIBRATION_TRANSLATION_M`], then
/// [`calibrate_offset`]. `None` with fewer than 3 moving pairs (a still camera, or
/// nothing registered).
#[must_use]
pub fn self_calibrate_offset(
    matches: &[FrameMatches],
    estimator: &dyn Estimator,
    seed: u64,
) -> Option<f64> {
    let moving = moving_pairs(matches, estimator, seed);
    (moving.len() >= 3).then(|| calibrate_offset(&moving))
}

/// [`self_calibrate_offset`] for the two-parameter [`DisparityCorrection`]
/// ([`calibrate_correction`]).
#[must_use]
pub fn self_calibrate_correction(
    matches: &[FrameMatches],
    estimator: &dyn Estimator,
    seed: u64,
) -> Option<DisparityCorrection> {
    let moving = moving_pairs(matches, estimator, seed);
    (moving.len() >= 3).then(|| calibrate_correction(&moving))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nelder_mead_finds_a_tilted_bowl() {
        let f = |v: [f64; 2]| (v[0] - 0.4 + 0.3 * v[1]).powi(2) * 50.0 + (v[1] - 3.0).powi(2);
        let [a, c] = nelder_mead(f, [[1.2, 0.0], [1.7, 0.0], [1.2, 1.5]], 200, 1e-6);
        assert!(
            (c - 3.0).abs() < 1e-3 && (a - (0.4 - 0.9)).abs() < 1e-3,
            "{a} {c}"
        );
    }
}
