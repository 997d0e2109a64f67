//! The least-squares pieces of the decision: a fit of some coefficients on a base, their
//! covariance, the covariance the rows' rotation terms carry, and the fraction of a
//! fitted correction that is applied.

use nalgebra::SMatrix;

use super::K;
use super::rows::RowDecision;
use super::subset::{solve_on, sub_matrix};
use crate::refine::evidence::{MatrixK, QuadraticCost, VectorK};

/// The minimiser of `q` over `base + Σ z_k e_k` for the coefficients `free`.
pub(super) fn fit_on_base(q: &QuadraticCost, base: &VectorK, free: &[usize]) -> VectorK {
    let n = free.len();
    let mut out = *base;
    if n == 0 {
        return out;
    }
    let rhs = q.b - q.a * base;
    if let Some(z) = solve_on(&q.a, &rhs, free) {
        for (&k, z) in free.iter().zip(z.iter()) {
            out[k] += z;
        }
    }
    out
}

/// The covariance of the coefficients `free` fitted on `q` (`A⁻¹` over them, χ² units so
/// pixels²), zero elsewhere; zero when `A` is singular there.
pub(super) fn covariance_on(q: &QuadraticCost, free: &[usize]) -> MatrixK {
    let n = free.len();
    let mut out = MatrixK::zeros();
    if n == 0 {
        return out;
    }
    let Some(chol) = sub_matrix(&q.a, free).cholesky() else {
        return out;
    };
    let inv = chol.inverse();
    for (i, &ki) in free.iter().enumerate() {
        for (j, &kj) in free.iter().enumerate() {
            out[(ki, kj)] = inv[(i, j)];
        }
    }
    if out.iter().all(|v| v.is_finite()) {
        out
    } else {
        MatrixK::zeros()
    }
}

/// The covariance of the calibration terms set by the rotation terms the rows support:
/// a yaw `f ψ` sets the offset and the quadratic coefficient to `−f ψ`, a roll `f θ` the
/// `y` coefficient, a pitch `f φ` the `x y` coefficient ([`RowDecision::correction`]).
pub(super) fn rows_covariance(rows: &RowDecision) -> MatrixK {
    // Column r: how each calibration term moves with rotation term r.
    let mut j = SMatrix::<f64, K, 3>::zeros();
    if rows.yaw {
        j[(0, 0)] = -1.0;
        j[(1, 0)] = -1.0;
    }
    if rows.roll {
        j[(3, 1)] = 1.0;
    }
    if rows.pitch {
        j[(4, 2)] = 1.0;
    }
    // Not scaled by the weight the terms are applied with (`rows.weight`): like the
    // rigidity terms', the uncertainty stays that of the fitted terms.
    let c = nalgebra::Matrix3::from_fn(|r, s| rows.rotation_covariance[r][s]);
    j * c * j.transpose()
}

/// The fraction of the fitted horizontal terms that is applied, from their held-out score
/// `relative` (χ² units, negative when they help) over `terms` terms, each chosen for
/// lowering it by more than `margin`: `w = clamp((−relative − terms · margin) / margin, 0, 1)`,
/// 0 when the score has just passed the margins and 1 from one margin beyond them; 0 when no
/// term is chosen or the score is not a number (nothing is applied).
///
/// A term chosen by a hair is a near tie with not choosing it. Applied in full, the
/// correction jumps between 0 and its fitted value as the evidence crosses the margin
/// from frame to frame, and the window rescales its keyframes by as much: on a straight
/// synthetic drive with an exact rig, a 0.09 px offset chosen for three frames moved the
/// newest pose 50 mm along a 10 m window. Weighted, the correction grows from 0 as its
/// evidence grows; evidence far beyond the margin (every real sequence here: hundreds
/// to thousands of χ² units) gets the full fit. A `margin` of 0 or less applies the fit
/// in full.
#[must_use]
pub fn applied_fraction(relative: f64, terms: usize, margin: f64) -> f64 {
    if terms == 0 {
        return 0.0;
    }
    if margin.is_nan() || margin <= 0.0 {
        return 1.0;
    }
    let excess = -relative - margin * terms as f64;
    if excess.is_nan() {
        return 0.0;
    }
    (excess / margin).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_applied_fraction_grows_with_the_evidence() {
        // One term: 0 at the margin, half at 1.5 margins, all from 2 margins.
        assert_eq!(applied_fraction(-10.0, 1, 10.0), 0.0);
        assert!((applied_fraction(-15.0, 1, 10.0) - 0.5).abs() < 1e-12);
        assert_eq!(applied_fraction(-20.0, 1, 10.0), 1.0);
        assert_eq!(applied_fraction(-5000.0, 1, 10.0), 1.0);
        // Two terms: each had to pass a margin.
        assert!((applied_fraction(-25.0, 2, 10.0) - 0.5).abs() < 1e-12);
        // Nothing chosen: nothing applied; no margin: the fit in full.
        assert_eq!(applied_fraction(0.0, 0, 10.0), 0.0);
        assert_eq!(applied_fraction(-1.0, 1, 0.0), 1.0);
        // A score that is not a number applies nothing.
        assert_eq!(applied_fraction(f64::NAN, 1, 10.0), 0.0);
        // Continuous and never decreasing as the score falls.
        let mut last = 0.0;
        for i in 0..400 {
            let w = applied_fraction(-f64::from(i) * 0.1, 1, 10.0);
            assert!((0.0..=1.0).contains(&w) && w >= last && w - last < 0.011);
            last = w;
        }
    }
}
