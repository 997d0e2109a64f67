//! The loops of the EM fit as [`simd::Kernel`]s: compiled for the target's baseline and
//! for the best instruction set of the CPU, the same operations and library calls in the
//! same order, so the same bits (issue 34).

use nalgebra::{Isometry3, Matrix3, Matrix6, Vector3, Vector6};

use super::{MIN_WEIGHT, NEGLIGIBLE, RangeNoise, Row, scoring_body};
use crate::estimators::mahalanobis::{Normal, determinant_and_inverse};
use crate::geometry::Correspondences;
use crate::simd;

/// One E step of [`super::em`] (its per-round constants computed by it): each row's posterior
/// inlier weight and information into `rows`, and the log-likelihood summed over the rows
/// in order. A [`simd::Kernel`], compiled for the best instruction set of the CPU (the same
/// operations and library calls, so the same bits).
pub(super) struct EStep<'a> {
    pub(super) data: &'a Correspondences,
    pub(super) rotation: &'a Matrix3<f64>,
    pub(super) translation: &'a Vector3<f64>,
    pub(super) noise: &'a RangeNoise,
    /// The isotropic model's determinant, information and half log-determinant.
    pub(super) isotropic: Option<(f64, Matrix3<f64>, f64)>,
    pub(super) ln_outlier: f64,
    pub(super) ln_prefactor: f64,
    pub(super) ln_bound: f64,
    pub(super) rows: &'a mut Vec<Row>,
}

impl simd::Kernel for EStep<'_> {
    type Output = f64;

    #[inline(always)]
    fn run(self) -> f64 {
        let Self {
            data,
            rotation,
            translation,
            noise,
            isotropic,
            ln_outlier,
            ln_prefactor,
            ln_bound,
            rows,
        } = self;
        let (src, dst) = (data.src(), data.dst());
        let mut log_likelihood = 0.0;
        rows.clear();
        for i in 0..data.len() {
            let q = rotation * src[i].coords;
            let e = dst[i].coords - q - translation;
            let (det, information, half_ln_det) = match isotropic {
                Some((det, w, half_ln_det)) => (det, Some(w), Some(half_ln_det)),
                None => {
                    let c = noise.residual_covariance(&q, &dst[i].coords);
                    let (det, w) = determinant_and_inverse(&c);
                    (det, w, None)
                }
            };
            // det ≥ (2f)³ (every other part of the covariance is positive semidefinite), so
            // a row that is negligible under that bound needs no logarithm.
            let gap = match information {
                Some(w) if det > 0.0 && det.is_finite() => {
                    let half_m = 0.5 * e.dot(&(w * e));
                    if ln_bound - half_m < -NEGLIGIBLE {
                        f64::NEG_INFINITY
                    } else {
                        let half_ln_det = half_ln_det.unwrap_or_else(|| 0.5 * det.ln());
                        ln_prefactor - half_ln_det - half_m - ln_outlier
                    }
                }
                _ => f64::NEG_INFINITY,
            };
            let weight = if gap < -NEGLIGIBLE {
                log_likelihood += ln_outlier;
                0.0
            } else {
                // ln(a + b) = ln b + ln(1 + a/b), a/b = e^gap.
                let ratio = gap.exp();
                log_likelihood += ln_outlier + ratio.ln_1p();
                ratio / (1.0 + ratio)
            };
            rows.push(Row {
                weight,
                information: information.unwrap_or_else(Matrix3::zeros),
            });
        }
        log_likelihood
    }
}

/// The normal equations of [`super::gauss_newton_step`]: a [`simd::Kernel`], compiled for the
/// best instruction set of the CPU (the same operations, so the same bits).
pub(super) struct WeightedNormalEquations<'a> {
    pub(super) data: &'a Correspondences,
    pub(super) pose: &'a Isometry3<f64>,
    pub(super) rows: &'a [Row],
}

impl simd::Kernel for WeightedNormalEquations<'_> {
    type Output = (Matrix6<f64>, Vector6<f64>);

    #[inline(always)]
    fn run(self) -> Self::Output {
        let mut normal = Normal::zeros();
        for (i, row) in self.rows.iter().enumerate() {
            if row.weight < MIN_WEIGHT {
                continue;
            }
            let w = row.information * row.weight;
            normal.add_point(self.pose, self.data, i, &w);
        }
        normal.parts()
    }
}

/// The sums `(Σ w |e|², Σ 3 w)` of [`super::isotropic_step`] over the rows of weight at least
/// `MIN_WEIGHT`, in order: a [`simd::Kernel`], compiled for the best instruction set of the CPU
/// (the same operations, so the same bits).
pub(super) struct IsotropicSums<'a> {
    pub(super) data: &'a Correspondences,
    pub(super) pose: &'a Isometry3<f64>,
    pub(super) rows: &'a [Row],
}

impl simd::Kernel for IsotropicSums<'_> {
    type Output = (f64, f64);

    #[inline(always)]
    fn run(self) -> Self::Output {
        let Self { data, pose, rows } = self;
        let (mut num, mut den) = (0.0, 0.0);
        for (i, row) in rows.iter().enumerate() {
            if row.weight < MIN_WEIGHT {
                continue;
            }
            num += row.weight * (data.dst()[i] - pose * data.src()[i]).norm_squared();
            den += 3.0 * row.weight;
        }
        (num, den)
    }
}

/// [`super::scoring_step`] as a kernel.
pub(super) struct Scoring<'a> {
    pub(super) data: &'a Correspondences,
    pub(super) pose: &'a Isometry3<f64>,
    pub(super) rows: &'a [Row],
    pub(super) noise: RangeNoise,
    pub(super) floor: f64,
}

impl simd::Kernel for Scoring<'_> {
    type Output = Option<RangeNoise>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        scoring_body(self.data, self.pose, self.rows, self.noise, self.floor)
    }
}
