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
        let mut h = Matrix6::<f64>::zeros();
        let mut g = Vector6::<f64>::zeros();
        // The rotation's matrix once per step, not once per row (the same bits).
        let r = self.pose.rotation.to_rotation_matrix();
        for &i in self.rows {
            let information =
                inverse3(&(r.matrix() * src_cov[i] * r.matrix().transpose() + dst_cov[i]));
            if let Some(w) = information {
                add_point(&mut h, &mut g, self.pose, self.data, i, &w);
            }
        }
        (h, g)
    }
}

/// Adds correspondence `i` of `data`, weighted by the 3x3 information `w` (1/m²), to the
/// normal equations `h`, `g` of a Gauss-Newton step on `pose` (the motion `dst = R src + t`)
/// perturbed on the left by `(ω, ν)` (radians, metres, in the destination frame): residual
/// `r = dst − pose·src`, Jacobian `[[q]×, −I]` with `q = pose·src`.
///
/// The same bits as `h += Jᵀ w J`, `g += Jᵀ w r` through nalgebra (issue 34), with the
/// Jacobian's zeros left out: nalgebra sums `P = Jᵀ w` and `P J` term by term in order,
/// and a term `0 · x` (`x` finite) is a zero, which leaves a sum unchanged unless the sum
/// is itself zero, when only its sign can differ; `h` and `g` start at `+0` in every caller
/// and never hold `-0` (`+0 + -0 = +0`), so such a zero adds nothing either way. When `w`
/// or `P` is not finite (`0 · ∞` is NaN) the full products are taken. Inlined into the
/// [`simd::Kernel`]s that call it.
#[inline(always)]
pub(crate) fn add_point(
    h: &mut Matrix6<f64>,
    g: &mut Vector6<f64>,
    pose: &Isometry3<f64>,
    data: &Correspondences,
    i: usize,
    w: &Matrix3<f64>,
) {
    let q = (pose * data.src()[i]).coords;
    let r = data.dst()[i].coords - q;
    let (q0, q1, q2) = (q[0], q[1], q[2]);
    let columns = &w.data.0; // columns[b][k] = w_kb
    // P = Jᵀ w (6 × 3) by columns, pc[b][a] = P[a][b] (h is column-major too, so each
    // update below is one 6-lane operation the compiler vectorises; the same operations
    // on every element as row by row): rows 0-2 from the columns of [q]×, whose zero is
    // left out; rows 3-5 are −w (−1 · x, the same bits as −x for finite x; the −0 terms
    // left out).
    let pc: [[f64; 6]; 3] = std::array::from_fn(|b| {
        let col = &columns[b];
        [
            q2 * col[1] + (-q1) * col[2],
            (-q2) * col[0] + q0 * col[2],
            q1 * col[0] + (-q0) * col[1],
            -col[0],
            -col[1],
            -col[2],
        ]
    });
    // P's rows 3-5 are −w, so P holds every entry of w. A sum with an infinite or NaN
    // term is ±∞ or NaN in any order, so these lane sums are all finite only when every
    // entry of P (and w) is; a sum that overflows merely takes the full products (the
    // same bits for finite w and P).
    let lanes: [f64; 6] = std::array::from_fn(|a| pc[0][a] + pc[1][a] + pc[2][a]);
    let total = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + (lanes[4] + lanes[5]);
    if !total.is_finite() {
        add_point_full(h, g, &q, &r, w);
        return;
    }
    // (P J)[a][c]: J's columns 0-2 are those of [q]×, 3-5 those of −I.
    let [p0, p1, p2] = &pc;
    let hc = &mut h.data.0; // hc[c][a] = h[(a, c)]
    for a in 0..6 {
        hc[0][a] += p1[a] * q2 + p2[a] * (-q1);
    }
    for a in 0..6 {
        hc[1][a] += p0[a] * (-q2) + p2[a] * q0;
    }
    for a in 0..6 {
        hc[2][a] += p0[a] * q1 + p1[a] * (-q0);
    }
    for (k, pk) in pc.iter().enumerate() {
        for a in 0..6 {
            hc[3 + k][a] += -pk[a];
        }
    }
    let (r0, r1, r2) = (r[0], r[1], r[2]);
    let gc = &mut g.data.0[0];
    for a in 0..6 {
        gc[a] += p0[a] * r0 + p1[a] * r1 + p2[a] * r2;
    }
}

/// [`add_point`] through nalgebra's products with the full Jacobian `[[q]×, −I]`.
fn add_point_full(
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

/// `pose` moved by the solution `δ = (ω, ν)` of `h δ = −g` ([`add_point`]'s
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

#[cfg(test)]
mod tests;
