//! Pieces shared by the estimators: residuals, inlier sets, the truncated cost and the
//! final SVD refinement on inliers.

use std::time::Instant;

use nalgebra::{Isometry3, Point3};

use super::{Diagnostics, Estimate};
use crate::arun::arun_pairs;
use crate::error::PoseError;
use crate::geometry::{Correspondences, MIN_CORRESPONDENCES, check_spread};
use crate::simd;

/// Squared residual `|d - (R s + t)|^2`, m².
#[inline(always)]
pub(crate) fn residual_sq(t: &Isometry3<f64>, s: &Point3<f64>, d: &Point3<f64>) -> f64 {
    (d - t * s).norm_squared()
}

/// Inlier tolerance on `|dst - (R src + t)|`, metres: one δ for every correspondence, or
/// one δ_i each (for example `3.4 σ_i` from a per-point noise level).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Tolerance<'a> {
    /// The same δ for all.
    Uniform(f64),
    /// δ_i for correspondence `i`.
    PerPoint(&'a [f64]),
}

impl Tolerance<'_> {
    /// δ_i, metres.
    #[inline(always)]
    #[must_use]
    pub fn at(&self, i: usize) -> f64 {
        match self {
            Tolerance::Uniform(d) => *d,
            Tolerance::PerPoint(v) => v[i],
        }
    }

    /// Least-squares weight of correspondence `i`: 1 for a uniform tolerance, `1 / δ_i²`
    /// (inverse variance, as δ_i is proportional to σ_i) per point.
    #[inline]
    #[must_use]
    pub fn weight(&self, i: usize) -> f64 {
        match self {
            Tolerance::Uniform(_) => 1.0,
            Tolerance::PerPoint(v) => v[i].powi(-2),
        }
    }
}

/// Writes into `out` the indices whose residual is below `threshold_m` (metres).
pub fn collect_inliers(
    data: &Correspondences,
    t: &Isometry3<f64>,
    threshold_m: f64,
    out: &mut Vec<usize>,
) {
    collect_inliers_within(data, t, Tolerance::Uniform(threshold_m), out);
}

/// Writes into `out` the indices `i` whose residual is below δ_i.
pub fn collect_inliers_within(
    data: &Correspondences,
    t: &Isometry3<f64>,
    tol: Tolerance<'_>,
    out: &mut Vec<usize>,
) {
    simd::dispatch(CollectInliers { data, t, tol, out });
}

/// [`collect_inliers_within`] as a [`simd::Kernel`], compiled for the best instruction set
/// of the CPU (the same operations, so the same rows; issue 34).
struct CollectInliers<'a> {
    data: &'a Correspondences,
    t: &'a Isometry3<f64>,
    tol: Tolerance<'a>,
    out: &'a mut Vec<usize>,
}

impl simd::Kernel for CollectInliers<'_> {
    type Output = ();

    #[inline(always)]
    fn run(self) {
        let Self { data, t, tol, out } = self;
        out.clear();
        // A loop, not `extend`: `Vec::extend` would run its loop out of line, compiled once.
        for (i, (s, d)) in data.src().iter().zip(data.dst()).enumerate() {
            if residual_sq(t, s, d) < tol.at(i).powi(2) {
                out.push(i);
            }
        }
    }
}

/// The MSAC cost `Σ min(r_i^2, δ^2)` over all correspondences, m².
#[must_use]
pub fn truncated_cost(data: &Correspondences, t: &Isometry3<f64>, threshold_m: f64) -> f64 {
    truncated_cost_within(data, t, Tolerance::Uniform(threshold_m))
}

/// The MSAC cost with per-correspondence tolerances, `Σ min(r_i^2, δ_i^2)`, m².
#[must_use]
pub fn truncated_cost_within(
    data: &Correspondences,
    t: &Isometry3<f64>,
    tol: Tolerance<'_>,
) -> f64 {
    data.src()
        .iter()
        .zip(data.dst())
        .enumerate()
        .map(|(i, (s, d))| residual_sq(t, s, d).min(tol.at(i).powi(2)))
        .sum()
}

/// RMS of the residuals over `indices`, metres (0 for an empty set).
#[must_use]
pub fn residual_rms(data: &Correspondences, t: &Isometry3<f64>, indices: &[usize]) -> f64 {
    if indices.is_empty() {
        return 0.0;
    }
    let sum: f64 = indices
        .iter()
        .map(|&i| residual_sq(t, &data.src()[i], &data.dst()[i]))
        .sum();
    (sum / indices.len() as f64).sqrt()
}

/// The estimate of a method with a fixed inlier threshold (metres): `transform`, fitted
/// on `inliers`, after `(iterations, cost evaluations)` of work started at `start`.
pub(crate) fn thresholded_estimate(
    data: &Correspondences,
    transform: Isometry3<f64>,
    inliers: Vec<usize>,
    threshold_m: f64,
    (iterations, cost_evaluations): (usize, u64),
    start: Instant,
) -> Estimate {
    Estimate {
        diagnostics: Diagnostics {
            iterations,
            cost_evaluations,
            final_cost: truncated_cost(data, &transform, threshold_m),
            residual_rms_m: residual_rms(data, &transform, &inliers),
            threshold_m: Some(threshold_m),
            elapsed: start.elapsed(),
            runner_up: None,
            range_noise: None,
        },
        transform,
        inliers,
    }
}

/// Arun on the correspondences at `indices` (equal weights).
pub(crate) fn arun_on(
    data: &Correspondences,
    indices: &[usize],
) -> Result<Isometry3<f64>, PoseError> {
    arun_within(data, indices, Tolerance::Uniform(1.0))
}

/// Arun on the correspondences at `indices`, weighted by [`Tolerance::weight`].
pub(crate) fn arun_within(
    data: &Correspondences,
    indices: &[usize],
    tol: Tolerance<'_>,
) -> Result<Isometry3<f64>, PoseError> {
    let (src, dst) = (data.src(), data.dst());
    arun_pairs(indices.iter().map(|&i| (&src[i], &dst[i], tol.weight(i))))
}

/// Fails with [`PoseError::InsufficientSupport`] below [`MIN_CORRESPONDENCES`] indices,
/// or [`PoseError::Degenerate`] when their source points are coincident or collinear.
pub(crate) fn check_support(data: &Correspondences, indices: &[usize]) -> Result<(), PoseError> {
    if indices.len() < MIN_CORRESPONDENCES {
        return Err(PoseError::InsufficientSupport {
            support: indices.len(),
            needed: MIN_CORRESPONDENCES,
        });
    }
    check_spread(indices.iter().map(|&i| &data.src()[i]), "inlier")
}

/// Validates an estimator's input: enough correspondences, neither set coincident or
/// collinear.
pub(crate) fn check_input(data: &Correspondences) -> Result<(), PoseError> {
    data.require(MIN_CORRESPONDENCES)?;
    check_spread(data.src(), "source")?;
    check_spread(data.dst(), "destination")
}

/// Refits on the inliers of `start` and repeats (new inliers at `threshold_m`, new fit)
/// (with per-point tolerances, the fit is weighted by `1 / δ_i²`)
/// until the set stops changing or `max_rounds` fits were made. Returns the pose and its
/// inliers; `inliers` is scratch space and holds the final set.
pub(crate) fn refine(
    data: &Correspondences,
    start: &Isometry3<f64>,
    threshold_m: f64,
    max_rounds: usize,
    inliers: &mut Vec<usize>,
) -> Result<Isometry3<f64>, PoseError> {
    refine_within(
        data,
        start,
        Tolerance::Uniform(threshold_m),
        max_rounds,
        inliers,
    )
}

/// [`refine`] with per-correspondence tolerances.
pub(crate) fn refine_within(
    data: &Correspondences,
    start: &Isometry3<f64>,
    tol: Tolerance<'_>,
    max_rounds: usize,
    inliers: &mut Vec<usize>,
) -> Result<Isometry3<f64>, PoseError> {
    collect_inliers_within(data, start, tol, inliers);
    check_support(data, inliers)?;
    let mut pose = arun_within(data, inliers, tol)?;
    let mut next = Vec::with_capacity(data.len());
    for _ in 1..max_rounds {
        collect_inliers_within(data, &pose, tol, &mut next);
        if next == *inliers {
            break;
        }
        if check_support(data, &next).is_err() {
            // The refit lost its support: keep the last supported fit.
            break;
        }
        std::mem::swap(inliers, &mut next);
        pose = arun_within(data, inliers, tol)?;
    }
    // The returned inliers are those of the returned pose.
    collect_inliers_within(data, &pose, tol, inliers);
    check_support(data, inliers)?;
    Ok(pose)
}

/// Validates a threshold in metres: finite and positive.
pub(crate) fn check_threshold(threshold_m: f64) -> Result<(), PoseError> {
    if threshold_m.is_finite() && threshold_m > 0.0 {
        Ok(())
    } else {
        Err(PoseError::InvalidConfig(format!(
            "threshold must be a positive number of metres, got {threshold_m}"
        )))
    }
}

#[cfg(test)]
mod tests {
    use nalgebra::Vector3;
    use rand::RngExt;

    use super::*;

    /// The inlier test before its kernel (issue 34), dispatched and baseline, on seeded random
    /// data with per-point tolerances (signed zeros and NaN among them).
    #[test]
    fn inliers_match_the_reference_in_every_instruction_set() {
        let mut rng = crate::rng::seeded(43);
        let mut selected = 0;
        for case in 0..100 {
            let n: usize = rng.random_range(3..200);
            let (src, dst) =
                crate::estimators::test_scenes::random_clouds(&mut rng, n, -3.0..3.0, 1.0..9.0);
            let data = Correspondences::new(src, dst).expect("valid");
            let t = Isometry3::new(
                Vector3::new(rng.random_range(-1.0..1.0), 0.0, 0.2),
                Vector3::new(0.0, rng.random_range(-0.5..0.5), 0.0),
            );
            let per_point: Vec<f64> = (0..n)
                .map(|_| match rng.random_range(0..30) {
                    0 => 0.0,
                    1 => -0.0,
                    2 => f64::NAN,
                    _ => rng.random_range(0.0..4.0),
                })
                .collect();
            let tol = if case % 2 == 0 {
                Tolerance::PerPoint(&per_point)
            } else {
                Tolerance::Uniform(rng.random_range(0.5..4.0))
            };
            let expected: Vec<usize> = data
                .src()
                .iter()
                .zip(data.dst())
                .enumerate()
                .filter(|(i, (s, d))| (*d - t * *s).norm_squared() < tol.at(*i).powi(2))
                .map(|(i, _)| i)
                .collect();
            selected += expected.len();
            let run = || {
                let mut out = vec![usize::MAX; 2];
                collect_inliers_within(&data, &t, tol, &mut out);
                out
            };
            assert_eq!(run(), expected, "case {case}");
            assert_eq!(crate::simd::baseline(run), expected, "case {case}");
        }
        assert!(selected > 0, "no row passed: the test compares empty lists");
    }
}
