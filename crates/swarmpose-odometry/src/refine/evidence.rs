//! What one pair of frames says about the disparity correction: the normal equations of
//! the pose and the correction after the points are eliminated (Schur complement), and
//! then the pose too, so that each pair contributes a quadratic model of its cost as a
//! function of the correction alone, the pose re-optimised for every correction
//! (the *profile* cost).

use nalgebra::{Matrix3, Matrix6, SMatrix, SVector, Vector3, Vector6};

use super::model::{CALIBRATION_TERMS, Matrix3x6, Matrix3xK};
use crate::nls::products;

/// K, the number of calibration terms.
const K: usize = CALIBRATION_TERMS;
/// 6xK matrix.
pub type Matrix6xK = SMatrix<f64, 6, K>;
/// KxK matrix.
pub type MatrixK = SMatrix<f64, K, K>;
/// K-vector.
pub type VectorK = SVector<f64, K>;

/// Normal equations of (pose, correction) with the points eliminated: for the cost
/// `F = ½ Σ w |e|²`, `H = Jᵀ W J` and `g = Jᵀ W e` reduced by each point's Schur
/// complement `H_xy − H_xp H_pp⁻¹ H_py`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Reduced {
    /// Pose block, 6x6.
    pub pose_pose: Matrix6<f64>,
    /// Pose-correction block, 6xK.
    pub pose_correction: Matrix6xK,
    /// Correction block, KxK.
    pub correction_correction: MatrixK,
    /// Pose gradient.
    pub pose_gradient: Vector6<f64>,
    /// Correction gradient.
    pub correction_gradient: VectorK,
}

impl Default for Reduced {
    fn default() -> Self {
        Self {
            pose_pose: Matrix6::zeros(),
            pose_correction: Matrix6xK::zeros(),
            correction_correction: MatrixK::zeros(),
            pose_gradient: Vector6::zeros(),
            correction_gradient: VectorK::zeros(),
        }
    }
}

impl std::ops::AddAssign<&Reduced> for Reduced {
    fn add_assign(&mut self, other: &Reduced) {
        self.pose_pose += other.pose_pose;
        self.pose_correction += other.pose_correction;
        self.correction_correction += other.correction_correction;
        self.pose_gradient += other.pose_gradient;
        self.correction_gradient += other.correction_gradient;
    }
}

/// One point's weighted Jacobian products, accumulated over its measurements.
#[derive(Debug, Clone, Copy)]
pub struct PointBlocks {
    /// `H_pp⁻¹`.
    pub pp_inv: Matrix3<f64>,
    /// `H_pT`.
    pub pose: Matrix3x6,
    /// `H_pc`.
    pub correction: Matrix3xK,
    /// `g_p`.
    pub gradient: Vector3<f64>,
}

/// A point's blocks for back-substitution on the pose alone: [`PointBlocks`] without
/// `H_pc`, which the pose's Levenberg-Marquardt never reads back (a third fewer bytes
/// kept per point and iteration, issue 34).
#[derive(Debug, Clone, Copy)]
pub(crate) struct PoseBlocks {
    /// `H_pp⁻¹`.
    pub(crate) pp_inv: Matrix3<f64>,
    /// `H_pT`.
    pub(crate) pose: Matrix3x6,
    /// `g_p`.
    pub(crate) gradient: Vector3<f64>,
}

impl PoseBlocks {
    /// The point's blocks with its `H_pc`.
    #[inline(always)]
    pub(crate) fn with_correction(&self, correction: Matrix3xK) -> PointBlocks {
        PointBlocks {
            pp_inv: self.pp_inv,
            pose: self.pose,
            correction,
            gradient: self.gradient,
        }
    }
}

impl Reduced {
    /// Adds the direct (pose, correction) terms of one measurement, `J_xᵀ w J_y` and
    /// `J_xᵀ w e`.
    ///
    /// The same bits as nalgebra's `pose.transpose() * pose * w` and the like, with the
    /// symmetric blocks computed on one triangle and mirrored ([`products`]).
    pub fn add_direct(&mut self, w: f64, pose: &Matrix3x6, corr: &Matrix3xK, e: &Vector3<f64>) {
        self.add_direct_with(w, pose, corr, e, false);
    }

    /// [`Reduced::add_direct`] for the pose blocks only (the correction's unchanged).
    pub fn add_direct_pose(&mut self, w: f64, pose: &Matrix3x6, e: &Vector3<f64>) {
        self.add_direct_pose_with(w, pose, e, false);
    }

    /// [`Reduced::add_direct`] on equations accumulated from [`Reduced::default`] by
    /// `add_direct*` and `eliminate*` alone ([`Reduced::has_negative_zero`]), the same bits
    /// (the refinement's forms, [`Reduced::add_reference_accumulated`] and
    /// [`Reduced::add_current_accumulated`], are compared with it in the tests).
    #[cfg(test)]
    pub(crate) fn add_direct_accumulated(
        &mut self,
        w: f64,
        pose: &Matrix3x6,
        corr: &Matrix3xK,
        e: &Vector3<f64>,
    ) {
        debug_assert!(!self.has_negative_zero(true));
        self.add_direct_with(w, pose, corr, e, true);
    }

    /// [`Reduced::add_direct_pose`] on equations accumulated from [`Reduced::default`] by
    /// `add_direct*` and `eliminate*` alone ([`Reduced::has_negative_zero`]), the same bits.
    #[cfg(test)]
    pub(crate) fn add_direct_pose_accumulated(
        &mut self,
        w: f64,
        pose: &Matrix3x6,
        e: &Vector3<f64>,
    ) {
        debug_assert!(!self.has_negative_zero(false));
        self.add_direct_pose_with(w, pose, e, true);
    }

    /// [`Reduced::add_direct_accumulated`] (with `corr`) or
    /// [`Reduced::add_direct_pose_accumulated`] (without) of a measurement in frame A,
    /// whose pose Jacobian `zero_pose` is zero: the same bits, its pose terms skipped
    /// exactly when those skip them (`w`, `e` and `corr` finite) without scanning the
    /// Jacobian for zeros (issue 34).
    #[inline(always)]
    pub(crate) fn add_reference_accumulated(
        &mut self,
        w: f64,
        zero_pose: &Matrix3x6,
        corr: Option<&Matrix3xK>,
        e: &Vector3<f64>,
    ) {
        debug_assert!(zero_pose.iter().all(|v| *v == 0.0));
        debug_assert!(!self.has_negative_zero(corr.is_some()));
        let finite = |m: &[f64]| m.iter().fold(true, |a, v| a & v.is_finite());
        let skip =
            w.is_finite() && finite(e.as_slice()) && corr.is_none_or(|c| finite(c.as_slice()));
        self.add_terms(w, zero_pose, corr, e, !skip);
    }

    /// [`Reduced::add_direct_accumulated`] (with `corr`) or
    /// [`Reduced::add_direct_pose_accumulated`] (without) of a measurement in frame B:
    /// the same bits with its pose terms always added. Where those forms skip them (a
    /// zero pose Jacobian and finite factors) each term is a sum of products with a zero
    /// factor, `±0`, and adding `±0` changes no entry of accumulated blocks, which hold
    /// no `−0` ([`Reduced::has_negative_zero`]); the check is not worth its cost for B,
    /// whose pose Jacobian is never zero in practice (issue 34).
    #[inline(always)]
    pub(crate) fn add_current_accumulated(
        &mut self,
        w: f64,
        pose: &Matrix3x6,
        corr: Option<&Matrix3xK>,
        e: &Vector3<f64>,
    ) {
        debug_assert!(!self.has_negative_zero(corr.is_some()));
        self.add_terms(w, pose, corr, e, true);
    }

    /// The terms of [`Reduced::add_direct_with`] (its correction's when `corr` is
    /// given), the pose's when `pose_terms`.
    #[inline(always)]
    fn add_terms(
        &mut self,
        w: f64,
        pose: &Matrix3x6,
        corr: Option<&Matrix3xK>,
        e: &Vector3<f64>,
        pose_terms: bool,
    ) {
        if pose_terms {
            products::add_gram(&mut self.pose_pose, pose, w);
            if let Some(corr) = corr {
                products::add_cross(&mut self.pose_correction, pose, corr, w);
            }
            products::add_cross(&mut self.pose_gradient, pose, e, w);
        }
        if let Some(corr) = corr {
            products::add_gram(&mut self.correction_correction, corr, w);
            products::add_cross(&mut self.correction_gradient, corr, e, w);
        }
    }

    /// [`Reduced::add_direct`]; `accumulated`: the blocks hold no `−0`
    /// ([`Reduced::has_negative_zero`]), so that need not be checked.
    #[inline(always)]
    fn add_direct_with(
        &mut self,
        w: f64,
        pose: &Matrix3x6,
        corr: &Matrix3xK,
        e: &Vector3<f64>,
        accumulated: bool,
    ) {
        if !self.zero_pose_terms_skippable(w, pose, e, Some(corr), accumulated) {
            products::add_gram(&mut self.pose_pose, pose, w);
            products::add_cross(&mut self.pose_correction, pose, corr, w);
            products::add_cross(&mut self.pose_gradient, pose, e, w);
        }
        products::add_gram(&mut self.correction_correction, corr, w);
        products::add_cross(&mut self.correction_gradient, corr, e, w);
    }

    /// [`Reduced::add_direct_pose`]; `accumulated` as in [`Reduced::add_direct_with`].
    #[inline(always)]
    fn add_direct_pose_with(
        &mut self,
        w: f64,
        pose: &Matrix3x6,
        e: &Vector3<f64>,
        accumulated: bool,
    ) {
        if !self.zero_pose_terms_skippable(w, pose, e, None, accumulated) {
            products::add_gram(&mut self.pose_pose, pose, w);
            products::add_cross(&mut self.pose_gradient, pose, e, w);
        }
    }

    /// No `−0` in the blocks ([`Reduced::has_negative_zero`]), as equations accumulated
    /// from zeros keep, for the tests.
    #[cfg(test)]
    pub(crate) fn accumulated(&self) -> bool {
        !self.has_negative_zero(true)
    }

    /// Whether a pose block (with `correction`, the pose-correction block too) holds a
    /// `−0`. Never for equations accumulated from [`Reduced::default`] (every entry `+0`)
    /// by `add_direct*` and `eliminate*` alone, so that the `_accumulated` forms need not
    /// look for one (issue 34): a floating sum `a + b` is `−0` only when `a` and `b` both
    /// are, and a difference `a − b` only when `a` is `−0` and `b` is `+0` (round to
    /// nearest), so an entry that is not `−0` never becomes `−0` by adding or subtracting
    /// anything.
    fn has_negative_zero(&self, correction: bool) -> bool {
        // Without early exits: these loops vectorise.
        let negative_zero = |m: &[f64]| {
            let neg = (-0.0_f64).to_bits();
            m.iter().fold(false, |a, v| a | (v.to_bits() == neg))
        };
        negative_zero(self.pose_pose.as_slice())
            | negative_zero(self.pose_gradient.as_slice())
            | (correction && negative_zero(self.pose_correction.as_slice()))
    }

    /// Whether the pose terms of a measurement with a zero pose Jacobian (frame A's) may
    /// be skipped without changing a bit: each of their entries is then a sum of
    /// products with a zero factor, `±0` when the other factors (`w`, `e`, `corr`) are
    /// finite, and adding `±0` changes no entry of the blocks but a `−0` (into `+0`).
    #[cfg(test)]
    fn zero_pose_terms_change_nothing(
        &self,
        w: f64,
        pose: &Matrix3x6,
        e: &Vector3<f64>,
        corr: Option<&Matrix3xK>,
    ) -> bool {
        self.zero_pose_terms_skippable(w, pose, e, corr, false)
    }

    /// [`Reduced::zero_pose_terms_change_nothing`], the blocks known to hold no `−0`
    /// when `accumulated` ([`Reduced::has_negative_zero`]).
    #[inline(always)]
    fn zero_pose_terms_skippable(
        &self,
        w: f64,
        pose: &Matrix3x6,
        e: &Vector3<f64>,
        corr: Option<&Matrix3xK>,
        accumulated: bool,
    ) -> bool {
        // Without early exits: these loops vectorise.
        let all_zero = |m: &[f64]| m.iter().fold(0_u64, |a, v| a | (v.to_bits() << 1)) == 0;
        let finite = |m: &[f64]| m.iter().fold(true, |a, v| a & v.is_finite());
        if !(all_zero(pose.as_slice()) && w.is_finite() && finite(e.as_slice())) {
            return false;
        }
        if corr.is_some_and(|c| !finite(c.as_slice())) {
            return false;
        }
        accumulated || !self.has_negative_zero(corr.is_some())
    }

    /// [`Reduced::eliminate`] for the pose blocks only (the correction's unchanged).
    pub fn eliminate_pose(&mut self, b: &PointBlocks) {
        self.eliminate_pose_blocks(&PoseBlocks {
            pp_inv: b.pp_inv,
            pose: b.pose,
            gradient: b.gradient,
        });
    }

    /// [`Reduced::eliminate_pose`] from the pose's blocks alone, the same bits.
    #[inline(always)]
    pub(crate) fn eliminate_pose_blocks(&mut self, b: &PoseBlocks) {
        let tp = products::tr_mul(&b.pose, &b.pp_inv);
        products::sub_product(&mut self.pose_pose, &tp, &b.pose);
        products::sub_product(&mut self.pose_gradient, &tp, &b.gradient);
    }

    /// Eliminates one point: subtracts `H_xp H_pp⁻¹ H_py` and `H_xp H_pp⁻¹ g_p`.
    #[inline(always)]
    pub fn eliminate(&mut self, b: &PointBlocks) {
        let tp = products::tr_mul(&b.pose, &b.pp_inv);
        let cp = products::tr_mul(&b.correction, &b.pp_inv);
        products::sub_product(&mut self.pose_pose, &tp, &b.pose);
        products::sub_product(&mut self.pose_correction, &tp, &b.correction);
        products::sub_product(&mut self.correction_correction, &cp, &b.correction);
        products::sub_product(&mut self.pose_gradient, &tp, &b.gradient);
        products::sub_product(&mut self.correction_gradient, &cp, &b.gradient);
    }

    /// Eliminates the pose too: the Hessian `I = H_cc − H_cT H_TT⁻¹ H_Tc` and gradient
    /// `γ = g_c − H_cT H_TT⁻¹ g_T` of the profile cost in the correction. `None` when
    /// the pose block is singular.
    #[must_use]
    pub fn profile(&self) -> Option<(MatrixK, VectorK)> {
        let inv = self.pose_pose.try_inverse()?;
        let ct = self.pose_correction.transpose() * inv;
        let info = self.correction_correction - ct * self.pose_correction;
        let grad = self.correction_gradient - ct * self.pose_gradient;
        Some((info, grad))
    }
}

/// A quadratic cost in the correction's coefficients `c` in canonical form,
/// `Q(c) = ½ cᵀ A c − bᵀ c` (constant dropped): the sum of pair profile costs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuadraticCost {
    /// `A`, KxK, symmetric positive semi-definite.
    pub a: MatrixK,
    /// `b`.
    pub b: VectorK,
}

impl Default for QuadraticCost {
    fn default() -> Self {
        Self {
            a: MatrixK::zeros(),
            b: VectorK::zeros(),
        }
    }
}

impl QuadraticCost {
    /// Adds the profile cost `γᵀ(c − c₀) + ½ (c − c₀)ᵀ I (c − c₀)` linearised at `c₀`,
    /// divided by `scale2` (the residuals' variance factor, so that costs are in χ²
    /// units whatever the true pixel noise).
    pub fn add(&mut self, info: &MatrixK, grad: &VectorK, at: &VectorK, scale2: f64) {
        self.a += info / scale2;
        self.b += (info * at - grad) / scale2;
    }

    /// Multiplies the cost by `k` (evidence that fades).
    pub fn scale(&mut self, k: f64) {
        self.a *= k;
        self.b *= k;
    }

    /// `Q(c)`.
    #[must_use]
    pub fn value(&self, c: &VectorK) -> f64 {
        0.5 * (c.transpose() * self.a * c)[0] - self.b.dot(c)
    }

    /// The sum of two quadratics.
    #[must_use]
    pub fn plus(&self, other: &Self) -> Self {
        Self {
            a: self.a + other.a,
            b: self.b + other.b,
        }
    }
}

#[cfg(test)]
#[path = "evidence_tests.rs"]
mod tests;
