//! The Gaussian prior that marginalised keyframes leave on the window's poses (see
//! [`super::marginal`], which makes it, and [`super::solve`], which adds it to the
//! system), and the calibration terms it is linearised at.

use nalgebra::{DMatrix, DVector, Vector6};

use super::Keyframe;
use crate::nls::pose::{Pose, unit_quaternion};
use crate::refine::evidence::{Matrix6xK, VectorK};
use crate::refine::model::{FOCAL_TERM, StereoModel};

/// A Gaussian prior on keyframe poses: half the robust cost it stands for is
/// `bᵀδ + ½ δᵀ H δ` (plus a constant), `δ` the poses' perturbations from their
/// linearisation point.
#[derive(Debug, Clone)]
pub(crate) struct Prior {
    /// Frame index of each pose, in the order of the blocks.
    pub(super) frames: Vec<usize>,
    /// The poses `T_kw` it was linearised at.
    pub(super) linearised: Vec<Pose>,
    /// `H`, `6 p` square for `p` poses (with the null space of a rigid motion of all).
    pub(super) information: DMatrix<f64>,
    /// `b`, the gradient of half the cost at the linearisation point and the terms `at`.
    pub(super) gradient: DVector<f64>,
    /// `∂b/∂c`, `6 p` rows, one column per calibration term.
    pub(super) calibration: DMatrix<f64>,
    /// The calibration terms it was linearised at ([`terms`]).
    pub(super) at: VectorK,
}

/// The model's calibration terms, in the order of the measurements' `∂e/∂c`: the
/// disparity correction's coefficients, then the focal length `fx` (pixels).
pub(crate) fn terms(model: &StereoModel) -> VectorK {
    let mut c = VectorK::zeros();
    for (i, v) in model
        .correction
        .coefficients()
        .iter()
        .enumerate()
        .take(FOCAL_TERM)
    {
        c[i] = *v;
    }
    c[FOCAL_TERM] = model.rig.fx;
    c
}

/// `δ` with `pose = E(δ) lin`: `ω = Log(R Rₗᵀ)`, `ν = t − R Rₗᵀ tₗ`. The logarithm is
/// taken from the exact quaternion (no `acos`, which loses small angles to rounding).
fn delta(pose: &Pose, lin: &Pose) -> Vector6<f64> {
    let r = pose.rot * lin.rot.transpose();
    let q = unit_quaternion(&r);
    let (w, v) = (q.w, q.imag());
    let (w, v) = if w < 0.0 { (-w, -v) } else { (w, v) };
    let s = v.norm();
    let omega = if s > 1e-12 {
        v * (2.0 * s.atan2(w) / s)
    } else {
        v * (2.0 / w)
    };
    let nu = pose.trans - r * lin.trans;
    Vector6::new(nu.x, nu.y, nu.z, omega.x, omega.y, omega.z)
}

impl Prior {
    /// Heap bytes held.
    pub(crate) fn heap_bytes(&self) -> usize {
        self.frames.capacity() * size_of::<usize>()
            + self.linearised.capacity() * size_of::<Pose>()
            + (self.information.len() + self.gradient.len() + self.calibration.len())
                * size_of::<f64>()
    }

    /// The slot in `frames` of each of the prior's poses, or `None` when one is missing.
    pub(super) fn on(&self, frames: &[Keyframe]) -> Option<Vec<usize>> {
        self.frames
            .iter()
            .map(|i| frames.iter().position(|f| f.index == *i))
            .collect()
    }

    /// The perturbations of the prior's poses at `poses` (by `slots`), stacked.
    pub(super) fn deltas(&self, slots: &[usize], poses: &[Pose]) -> DVector<f64> {
        let mut d = DVector::zeros(6 * slots.len());
        for (i, (s, lin)) in slots.iter().zip(&self.linearised).enumerate() {
            d.fixed_rows_mut::<6>(6 * i)
                .copy_from(&delta(&poses[*s], lin));
        }
        d
    }

    /// The gradient at the linearisation point with the calibration terms `c`.
    fn gradient_at(&self, c: &VectorK) -> DVector<f64> {
        &self.gradient + &self.calibration * (c - self.at)
    }

    /// The robust cost's units (twice half the cost) at `poses` with the calibration
    /// terms `c`, but for a constant: `2 bᵀδ + δᵀ H δ`.
    pub(super) fn energy(&self, slots: &[usize], poses: &[Pose], c: &VectorK) -> f64 {
        let d = self.deltas(slots, poses);
        2.0 * self.gradient_at(c).dot(&d) + d.dot(&(&self.information * &d))
    }

    /// Adds the prior (its poses at `slots` of `poses`) to a system over the poses after
    /// the first `fixed` slots (held fixed: conditioned on), with the calibration terms
    /// `c`: `S += H`, `g += b + S_ξc (c − c_lin) + H δ` and the pose-calibration blocks
    /// `pose_calibration += S_ξc` on the rows of the free poses.
    pub(super) fn add_to(
        &self,
        (slots, poses, fixed): (&[usize], &[Pose], usize),
        c: &VectorK,
        (s, g): (&mut DMatrix<f64>, &mut DVector<f64>),
        pose_calibration: &mut [Matrix6xK],
    ) {
        let d = self.deltas(slots, poses);
        let gp = self.gradient_at(c) + &self.information * d;
        for (i, si) in slots.iter().enumerate() {
            let Some(vi) = si.checked_sub(fixed) else {
                continue;
            };
            let mut rows = g.fixed_rows_mut::<6>(6 * vi);
            rows += gp.fixed_rows::<6>(6 * i);
            if let Some(pc) = pose_calibration.get_mut(vi) {
                *pc += self.calibration.fixed_rows::<6>(6 * i);
            }
            for (j, sj) in slots.iter().enumerate() {
                let Some(vj) = sj.checked_sub(fixed) else {
                    continue;
                };
                let mut block = s.fixed_view_mut::<6, 6>(6 * vi, 6 * vj);
                block += self.information.fixed_view::<6, 6>(6 * i, 6 * j);
            }
        }
    }
}
