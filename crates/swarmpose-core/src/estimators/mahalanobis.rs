//! Final refinement on per-point noise covariances (anisotropic noise).
//!
//! With covariances `Σ_s,i` (of `src_i`, source frame) and `Σ_d,i` (of `dst_i`,
//! destination frame) attached to the correspondences
//! ([`Correspondences::with_noise_covariance`]), a correct match has the residual
//! `r_i = d_i - (R s_i + t)` with covariance `Σ_i = R Σ_s,i Rᵀ + Σ_d,i`. The motion of
//! maximum likelihood minimises
//!
//! ```text
//! Σ_i r_iᵀ Σ_i⁻¹ r_i    over the inliers  r_iᵀ Σ_i⁻¹ r_i < g,
//! ```
//!
//! with the gate `g` a χ²(3) quantile. No closed form exists (Arun's SVD assumes one
//! isotropic σ per point), so each round selects the inliers and takes Gauss-Newton steps
//! with the left perturbation `R' = exp([ω]ₓ) R`, `t' = exp([ω]ₓ) t + δt`, whose Jacobian
//! is `∂r/∂(ω, δt) = ([R s + t]ₓ, -I)`. The covariances are re-rotated at every step.
//! The gate opens at 16 g, then 4 g, then g, because the starting motion comes from an
//! isotropic test. For stereo points, whose noise is elongated along the viewing ray,
//! this lets the precise lateral positions of far points count without their depth noise
//! pulling the translation.

use nalgebra::{Isometry3, Matrix3, Matrix3x6, Matrix6, Translation3, UnitQuaternion, Vector6};

use crate::error::PoseError;
use crate::geometry::{Correspondences, CovariancePair, MIN_CORRESPONDENCES};
use crate::simd;
pub(crate) use normal::Normal;

/// 99 % quantile of χ² with 3 degrees of freedom, the default gate: `3.368²`, the square
/// of the isotropic threshold multiplier.
pub const CHI2_3_99: f64 = 11.345;

/// Gauss-Newton steps per inlier selection.
const STEPS_PER_ROUND: usize = 5;

/// Refines `start` on the covariances attached to `data` (see the module documentation):
/// up to `rounds` (at least 3) rounds of gating at `gate` (χ²(3) units, for example
/// [`CHI2_3_99`]) and Gauss-Newton steps. Returns the motion and its inliers (ascending).
///
/// # Errors
/// [`PoseError::InvalidConfig`] when `data` carries no covariances or `gate` is not
/// positive; [`PoseError::InsufficientSupport`] when fewer than
/// [`MIN_CORRESPONDENCES`] correspondences pass the gate.
pub fn refine_mahalanobis(
    data: &Correspondences,
    start: &Isometry3<f64>,
    gate: f64,
    rounds: usize,
) -> Result<(Isometry3<f64>, Vec<usize>), PoseError> {
    let Some((src_cov, dst_cov)) = data.noise_covariance() else {
        return Err(PoseError::InvalidConfig(
            "the Mahalanobis refinement needs per-point noise covariances".into(),
        ));
    };
    if !(gate.is_finite() && gate > 0.0) {
        return Err(PoseError::InvalidConfig(format!(
            "the Mahalanobis gate must be positive, got {gate}"
        )));
    }
    let select = |pose: &Isometry3<f64>, gate: f64, out: &mut Vec<usize>| {
        simd::dispatch(Select {
            pose,
            data,
            covariance: (src_cov, dst_cov),
            gate,
            out,
        });
    };
    let schedule = |round: usize| gate * [16.0, 4.0].get(round).copied().unwrap_or(1.0);
    let too_few = |got: usize| PoseError::InsufficientSupport {
        support: got,
        needed: MIN_CORRESPONDENCES,
    };
    let mut pose = *start;
    let mut inliers = Vec::with_capacity(data.len());
    let mut next = Vec::with_capacity(data.len());
    select(&pose, schedule(0), &mut inliers);
    for round in 0..rounds.max(3) {
        if inliers.len() < MIN_CORRESPONDENCES {
            return Err(too_few(inliers.len()));
        }
        for _ in 0..STEPS_PER_ROUND {
            let (h, g) = simd::dispatch(NormalEquations {
                pose: &pose,
                data,
                covariance: (src_cov, dst_cov),
                rows: &inliers,
            });
            let Some((moved, step)) = gauss_newton_step(&pose, &h, &g) else {
                break;
            };
            pose = moved;
            if step < 1e-10 {
                break;
            }
        }
        select(&pose, schedule(round + 1), &mut next);
        if next == inliers && round >= 2 {
            break;
        }
        std::mem::swap(&mut inliers, &mut next);
    }
    select(&pose, gate, &mut inliers);
    if inliers.len() < MIN_CORRESPONDENCES {
        return Err(too_few(inliers.len()));
    }
    Ok((pose, inliers))
}

/// The rows of `data` within the χ²(3) gate `gate` of `pose` (ascending, into `out`): those
/// whose residual `r` has `rᵀ (R Σ_s Rᵀ + Σ_d)⁻¹ r < gate`. A [`simd::Kernel`], compiled for
/// the best instruction set of the CPU (the same operations, so the same rows; issue 34).
struct Select<'a> {
    pose: &'a Isometry3<f64>,
    data: &'a Correspondences,
    covariance: CovariancePair<'a>,
    gate: f64,
    out: &'a mut Vec<usize>,
}

impl simd::Kernel for Select<'_> {
    type Output = ();

    #[inline(always)]
    fn run(self) {
        let Self {
            pose,
            data,
            covariance: (src_cov, dst_cov),
            gate,
            out,
        } = self;
        let rot = pose.rotation.to_rotation_matrix();
        out.clear();
        for i in 0..data.len() {
            let r = data.dst()[i] - pose * data.src()[i];
            // rᵀ Σ⁻¹ r ≥ |r|² / tr Σ (tr Σ_s is rotation-invariant): most wrong matches
            // fail without an inversion.
            if r.norm_squared() < gate * (src_cov[i].trace() + dst_cov[i].trace())
                && inverse3(&(rot.matrix() * src_cov[i] * rot.matrix().transpose() + dst_cov[i]))
                    .is_some_and(|w| r.dot(&(w * r)) < gate)
            {
                out.push(i);
            }
        }
    }
}

/// The normal equations `(h, g)` of a Gauss-Newton step on `pose` over `rows` of `data`,
/// each weighted by its information `(R Σ_s Rᵀ + Σ_d)⁻¹` (rows whose covariance is
/// singular left out), in the order of `rows`: a [`simd::Kernel`], compiled for the best
/// instruction set of the CPU (the same operations, so the same bits).
struct NormalEquations<'a> {
    pose: &'a Isometry3<f64>,
    data: &'a Correspondences,
    covariance: CovariancePair<'a>,
    rows: &'a [usize],
}

impl simd::Kernel for NormalEquations<'_> {
    type Output = (Matrix6<f64>, Vector6<f64>);

    #[inline(always)]
    fn run(self) -> Self::Output {
        let (src_cov, dst_cov) = self.covariance;
        let mut normal = Normal::zeros();
        // The rotation's matrix once per step, not once per row (the same bits).
        let r = self.pose.rotation.to_rotation_matrix();
        for &i in self.rows {
            let information =
                inverse3(&(r.matrix() * src_cov[i] * r.matrix().transpose() + dst_cov[i]));
            if let Some(w) = information {
                normal.add_point(self.pose, self.data, i, &w);
            }
        }
        normal.parts()
    }
}

/// [`Normal::add_point`] through nalgebra's products with the full Jacobian `[[q]×, −I]`.
pub(crate) fn add_point_full(
    h: &mut Matrix6<f64>,
    g: &mut Vector6<f64>,
    q: &nalgebra::Vector3<f64>,
    r: &nalgebra::Vector3<f64>,
    w: &Matrix3<f64>,
) {
    let mut j = Matrix3x6::<f64>::zeros();
    j.fixed_view_mut::<3, 3>(0, 0).copy_from(&q.cross_matrix());
    j.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-Matrix3::identity()));
    *h += j.transpose() * w * j;
    *g += j.transpose() * w * r;
}

/// The determinant and the inverse (`None` when the determinant is zero) of a 3 × 3
/// matrix: nalgebra's `determinant()` and `try_inverse()` for three dimensions, the same
/// operations in the same order (so the same bits), with the determinant computed once and
/// inline (issue 34: the estimator inverts a covariance per row and round).
#[inline(always)]
pub(crate) fn determinant_and_inverse(m: &Matrix3<f64>) -> (f64, Option<Matrix3<f64>>) {
    let [[m11, m21, m31], [m12, m22, m32], [m13, m23, m33]] = m.data.0;
    let minor_m12_m23 = m22 * m33 - m32 * m23;
    let minor_m11_m23 = m21 * m33 - m31 * m23;
    let minor_m11_m22 = m21 * m32 - m31 * m22;
    let determinant = m11 * minor_m12_m23 - m12 * minor_m11_m23 + m13 * minor_m11_m22;
    if determinant == 0.0 {
        return (determinant, None);
    }
    let inverse = Matrix3::new(
        minor_m12_m23 / determinant,
        (m13 * m32 - m33 * m12) / determinant,
        (m12 * m23 - m22 * m13) / determinant,
        -minor_m11_m23 / determinant,
        (m11 * m33 - m31 * m13) / determinant,
        (m13 * m21 - m23 * m11) / determinant,
        minor_m11_m22 / determinant,
        (m12 * m31 - m32 * m11) / determinant,
        (m11 * m22 - m21 * m12) / determinant,
    );
    (determinant, Some(inverse))
}

/// [`determinant_and_inverse`]'s inverse: nalgebra's `try_inverse()` for 3 × 3, inline.
#[inline(always)]
pub(crate) fn inverse3(m: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    determinant_and_inverse(m).1
}

/// `pose` moved by the solution `δ = (ω, ν)` of `h δ = −g` ([`Normal::add_point`]'s
/// perturbation), and `|δ|`; `None` when `h` is singular or the step is not finite.
pub(crate) fn gauss_newton_step(
    pose: &Isometry3<f64>,
    h: &Matrix6<f64>,
    g: &Vector6<f64>,
) -> Option<(Isometry3<f64>, f64)> {
    let delta = h.lu().solve(&(-g))?;
    if !delta.iter().all(|v| v.is_finite()) {
        return None;
    }
    let dr = UnitQuaternion::from_scaled_axis(delta.fixed_rows::<3>(0).into_owned());
    let dt = delta.fixed_rows::<3>(3).into_owned();
    let moved = Isometry3::from_parts(
        Translation3::from(dr * pose.translation.vector + dt),
        dr * pose.rotation,
    );
    Some((moved, delta.norm()))
}

mod normal;
#[cfg(test)]
mod tests;
