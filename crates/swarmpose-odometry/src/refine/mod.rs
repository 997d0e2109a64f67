//! Reprojection refinement: the motion between two stereo frames that best explains the
//! measured pixels, a two-frame bundle adjustment.
//!
//! Unknowns: the pose of the reference frame A in the current frame B (6 parameters) and
//! every matched point, anchored in A by inverse depth ([`model`]). Each point is
//! measured in both frames as `(u, v, d)`, so it contributes 6 whitened residuals for 3
//! parameters of its own. Levenberg-Marquardt on the pose, with the points eliminated by
//! their 3x3 Schur complements at every step (`O(N)` per iteration), and a Huber loss on
//! each measurement's whitened residual norm. Rounds of gating (a point whose χ² over
//! its 3 degrees of freedom exceeds [`RefineConfig::gate_chi2`] is dropped) and refit
//! follow until the inliers settle.
//!
//! The covariance of the motion is `k S⁻¹`, where `S` is the pose block of the
//! information matrix after the points are eliminated and `k` the larger of the
//! residuals' variance factor `s² = Σ w |e|² / (3 N − 6)` (1 when the pixel noise is as
//! modelled) and the regions' factor of [`noise`] (errors shared by the features of a
//! region of the image, which `s²` counts as independent; docs/covariance.md). It is the
//! covariance of `ξ = (ν, ω)` (metres, radians) in `T_true = T_est ∘ E(ξ)`, where `E(ξ)`
//! maps `P ↦ Exp(ω) P + ν`: `R_true = R_est Exp(ω)`, `t_true = t_est + R_est ν`, both
//! vectors in the frame of the current camera B.

pub mod evidence;
pub mod floor;
pub mod model;
pub mod noise;
mod prepared;
mod rounds;
pub mod split;

use nalgebra::{Isometry3, Matrix6, Vector3, Vector6};

use evidence::{PoseBlocks, Reduced};
use model::{Linearized, Parts, StereoModel, StereoObservation};
pub(crate) use prepared::Prepared;

use crate::nls::lm::{Damping, LeastSquares};
use crate::nls::pose::Pose;
use crate::nls::products;
use crate::nls::robust::{huber_cost, huber_weight};
use crate::nls::schur::{back_substitute, point_inverse};
use swarmpose_vision::simd::dispatch;

/// Settings of the refinement.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct RefineConfig {
    /// Most Levenberg-Marquardt iterations per round (default 10).
    pub max_iterations: usize,
    /// Rounds of gating and refitting (default 3).
    pub rounds: usize,
    /// Huber threshold on a measurement's whitened residual norm (default 2.5; about the
    /// 85th percentile of the norm of a 3-vector of standard normals).
    pub huber_k: f64,
    /// Largest χ² of an inlier over its 6 residuals less 3 point parameters (default
    /// 16.27, the χ²(3) 99.9 % quantile).
    pub gate_chi2: f64,
    /// Gate of the first round, at the estimator's motion (default 100: the estimator's
    /// motion is only approximately right); the first round also keeps every match up to
    /// the median χ², so that a rough start keeps the better half.
    pub initial_gate_chi2: f64,
    /// Most Gauss-Newton iterations of the alignment that moves each match's measurement
    /// in the current frame to where the reference's image patch appears, to a fraction
    /// of a pixel, before the refinement (when both frames come with images; default 10).
    pub align_iterations: usize,
    /// Largest move of that alignment from the matched keypoint, pixels (default 2.0);
    /// a match whose patch would move further is left out of the refinement.
    pub align_max_move_px: f32,
}

impl Default for RefineConfig {
    fn default() -> Self {
        Self {
            max_iterations: 10,
            rounds: 3,
            huber_k: 2.5,
            gate_chi2: 16.27,
            initial_gate_chi2: 100.0,
            align_iterations: 10,
            align_max_move_px: 2.0,
        }
    }
}

/// Why a refinement failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RefineError {
    /// Fewer inliers than the minimum.
    #[error("{got} points consistent with the motion, fewer than {needed}")]
    TooFewInliers {
        /// Inliers found.
        got: usize,
        /// Minimum.
        needed: usize,
    },
    /// The information matrix of the pose is singular (degenerate geometry).
    #[error("the pose is not determined by the points (singular information matrix)")]
    Singular,
    /// The two slices of measurements differ in length.
    #[error("{reference} reference measurements for {current} current ones")]
    LengthMismatch {
        /// Reference measurements.
        reference: usize,
        /// Current measurements.
        current: usize,
    },
}

/// A refined motion.
#[derive(Debug, Clone, PartialEq)]
pub struct Refined {
    /// The pose of the current camera B in the reference camera A, `T_AB`
    /// (`P_A = R P_B + t`, metres).
    pub motion: Isometry3<f64>,
    /// Covariance of the motion's perturbation `ξ = (ν, ω)` (module documentation).
    pub covariance: Matrix6<f64>,
    /// Indices of the inlier matches, ascending.
    pub inliers: Vec<usize>,
    /// The refined point of each inlier, anchored in A by inverse depth `(x, y, ρ)`
    /// ([`model`]).
    pub points: Vec<Vector3<f64>>,
    /// Residuals' variance factor `s²` (1 when the pixel noise is as modelled).
    pub scale2: f64,
    /// The regions' variance factor ([`noise::cluster_factor`]: errors shared by the
    /// features of a region of the image counted), `None` with too few inliers. The
    /// covariance is `max(s², this) S⁻¹`.
    pub cluster_factor: Option<f64>,
    /// Levenberg-Marquardt iterations over all rounds.
    pub iterations: usize,
    /// The normal equations of (pose, correction) with the points eliminated, at the
    /// solution, per fold of the matches (see [`refine`]).
    pub reduced: [Reduced; 2],
}

impl Refined {
    /// The motion's covariance with the calibration's added: the motion moves with the
    /// calibration terms `c` as `∂ξ/∂c = −S_ξξ⁻¹ S_ξc` (the reduced normal equations of
    /// both folds), so their covariance `calibration` (pixels², [`evidence::MatrixK`])
    /// adds `G Σ_c Gᵀ`.
    #[must_use]
    pub fn covariance_with_calibration(&self, calibration: &evidence::MatrixK) -> Matrix6<f64> {
        let mut both = self.reduced[0];
        both += &self.reduced[1];
        let Some(inv) = both.pose_pose.try_inverse() else {
            return self.covariance;
        };
        let g = inv * both.pose_correction;
        let added = g * calibration * g.transpose();
        let out = self.covariance + (added + added.transpose()) * 0.5;
        if out.iter().all(|v| v.is_finite()) {
            out
        } else {
            self.covariance
        }
    }
}

/// `T_BA` moved by the step `ξ = (ν, ω)` of the pose block: `P_B ← Exp(ω) P_B + ν`.
#[inline(always)]
fn moved(pose: &Pose, xi: &Vector6<f64>) -> Pose {
    pose.moved(
        &Vector3::new(xi[0], xi[1], xi[2]),
        &Vector3::new(xi[3], xi[4], xi[5]),
    )
}

/// The two measurements of one point, linearised (the Jacobians of `parts`), or `None`
/// if B cannot see it. Inlined into each caller, where `parts` is a constant: the
/// Jacobians it leaves zero are then neither written nor copied (issue 34).
#[inline(always)]
fn linearize(
    model: &Prepared,
    pose: &Pose,
    p: &Vector3<f64>,
    a: &StereoObservation,
    b: &StereoObservation,
    parts: Parts,
) -> Option<(Linearized, Linearized)> {
    Some((
        model.in_reference_parts(p, a, parts),
        model.in_current_parts(&pose.rot, &pose.trans, p, b, parts)?,
    ))
}

/// A match's point fitted to a pose ([`fit_point`]) and the squared whitened residual
/// norms of its measurements in A and in B there (their sum its χ²), or `None`.
type Fitted = Option<(Vector3<f64>, f64, f64)>;

/// Best point for a fixed pose: Gauss-Newton on its 6 residuals from `p`, with the
/// squared whitened residual norms in A and in B at the point found.
#[inline(always)]
fn fit_point(
    model: &Prepared,
    pose: &Pose,
    mut p: Vector3<f64>,
    a: &StereoObservation,
    b: &StereoObservation,
) -> Fitted {
    for _ in 0..2 {
        let (la, lb) = linearize(model, pose, &p, a, b, Parts::Point)?;
        // `aᵀ a + bᵀ b` as nalgebra sums it, without the transposed copies ([`products`]).
        let (da, db) = (&la.d_point, &lb.d_point);
        let h = products::tr_mul(da, da) + products::tr_mul(db, db);
        let g = products::tr_mul(da, &la.residual) + products::tr_mul(db, &lb.residual);
        p -= h.try_inverse()? * g;
    }
    let (a2, b2) = model.residuals2(&pose.rot, &pose.trans, &p, a, b)?;
    Some((p, a2, b2))
}

/// Working state of one round.
struct Problem<'a> {
    model: &'a Prepared,
    config: &'a RefineConfig,
    reference: &'a [StereoObservation],
    current: &'a [StereoObservation],
    active: Vec<usize>,
}

impl Problem<'_> {
    /// Robust cost `½ Σ ρ` of the active points at `pose` with `points`.
    #[inline(always)]
    fn cost(&self, pose: &Pose, points: &[Vector3<f64>]) -> f64 {
        let k = self.config.huber_k;
        let mut total = 0.0;
        for (&i, p) in self.active.iter().zip(points) {
            match self.model.residuals2(
                &pose.rot,
                &pose.trans,
                p,
                &self.reference[i],
                &self.current[i],
            ) {
                Some((a2, b2)) => total += huber_cost(a2, k) + huber_cost(b2, k),
                None => return f64::INFINITY,
            }
        }
        0.5 * total
    }

    /// The reduced system at `pose`, with each point's blocks for back-substitution;
    /// `None` if a point left B's view or a block is singular. With `parts` other than
    /// [`Parts::All`] only the pose blocks are computed (the correction's stay zero),
    /// the same bit for bit. Inlined into its two callers, each with `parts` constant
    /// (issue 34).
    /// With `scores`, each match's Huber-weighted χ² is added to its first value and
    /// its score on the pose ([`noise::Score`]) pushed to its second, from the same
    /// linearisation.
    #[inline(always)]
    fn build(
        &self,
        pose: &Pose,
        points: &[Vector3<f64>],
        folds: Option<&[u8]>,
        blocks: &mut Vec<PoseBlocks>,
        parts: Parts,
        mut scores: Option<&mut (f64, Vec<noise::Score>)>,
    ) -> Option<[Reduced; 2]> {
        let k = self.config.huber_k;
        let mut reduced = [Reduced::default(); 2];
        blocks.clear();
        let all = parts == Parts::All;
        for (&i, p) in self.active.iter().zip(points) {
            let (la, lb) = linearize(
                self.model,
                pose,
                p,
                &self.reference[i],
                &self.current[i],
                parts,
            )?;
            let wa = huber_weight(la.residual.norm_squared(), k);
            let wb = huber_weight(lb.residual.norm_squared(), k);
            // The nalgebra expressions `aᵀ b w + …`, bit for bit ([`products`]).
            let hpp = products::gram(&la.d_point, wa) + products::gram(&lb.d_point, wb);
            let b = PoseBlocks {
                pp_inv: point_inverse(&hpp)?,
                pose: products::cross(&lb.d_point, &lb.d_pose, wb),
                gradient: products::cross(&la.d_point, &la.residual, wa)
                    + products::cross(&lb.d_point, &lb.residual, wb),
            };
            let fold = folds.map_or(0, |f| usize::from(f[i] & 1));
            let r = &mut reduced[fold];
            // `reduced` is accumulated from zeros by these alone: it holds no `−0` (evidence.rs).
            // A's pose Jacobian is zero; B's is not ([`Reduced::add_current_accumulated`]).
            if all {
                r.add_reference_accumulated(wa, &la.d_pose, Some(&la.d_correction), &la.residual);
                r.add_current_accumulated(wb, &lb.d_pose, Some(&lb.d_correction), &lb.residual);
                let hpc = products::cross(&la.d_point, &la.d_correction, wa)
                    + products::cross(&lb.d_point, &lb.d_correction, wb);
                r.eliminate(&b.with_correction(hpc));
            } else {
                r.add_reference_accumulated(wa, &la.d_pose, None, &la.residual);
                r.add_current_accumulated(wb, &lb.d_pose, None, &lb.residual);
                r.eliminate_pose_blocks(&b);
            }
            if let Some((chi2, scores)) = scores.as_deref_mut() {
                let (sa, sb) = (la.residual.norm_squared(), lb.residual.norm_squared());
                *chi2 += huber_weight(sa, k) * sa + wb * sb;
                scores.push(score(&self.current[i], &lb, wb, &b));
            }
            blocks.push(b);
        }
        Some(reduced)
    }

    /// Levenberg-Marquardt from `pose` and `points`, whose cost ([`Problem::cost`]) is
    /// `cost`, in the buffers `work`; returns the iterations done.
    #[inline(always)]
    fn solve(
        &self,
        pose: &mut Pose,
        points: &mut Vec<Vector3<f64>>,
        cost: f64,
        work: &mut Work,
    ) -> Result<usize, RefineError> {
        // As large as `points` (written whole before it is read).
        work.trial.clear();
        work.trial.extend_from_slice(points);
        let mut lm = PairLm {
            problem: self,
            blocks: &mut work.blocks,
            trial: &mut work.trial,
            pose,
            points,
            cost,
            system: (Matrix6::zeros(), Vector6::zeros()),
            step: (Vector6::zeros(), None),
        };
        PAIR_DAMPING.minimise(&mut lm, self.config.max_iterations)
    }
}

/// The damping of the pair refinement: from 10⁻⁴, stalled at 10⁸.
const PAIR_DAMPING: Damping = Damping {
    start: 1e-4,
    ceiling: 1e8,
    ceiling_tried: false,
};

/// The buffers of a refinement's rounds, kept from round to round (issue 34: two
/// allocations a round), each as large as the matches.
pub(super) struct Work {
    /// Each active point's blocks for back-substitution.
    blocks: Vec<PoseBlocks>,
    /// The points moved by the last step.
    trial: Vec<Vector3<f64>>,
}

/// One round's Levenberg-Marquardt state: the pose and the active points, moved in
/// place, with the reduced pose system of the last linearisation.
struct PairLm<'p, 'a> {
    problem: &'p Problem<'a>,
    pose: &'p mut Pose,
    points: &'p mut Vec<Vector3<f64>>,
    /// Each point's blocks for back-substitution.
    blocks: &'p mut Vec<PoseBlocks>,
    /// The points moved by the last step.
    trial: &'p mut Vec<Vector3<f64>>,
    /// The robust cost at `pose`, `points`.
    cost: f64,
    /// The reduced pose system `(S, g)`.
    system: (Matrix6<f64>, Vector6<f64>),
    /// The last step `δξ` and the pose it leads to with its cost.
    step: (Vector6<f64>, Option<(Pose, f64)>),
}

impl LeastSquares for PairLm<'_, '_> {
    type Error = RefineError;

    #[inline(always)]
    fn linearise(&mut self) -> Result<f64, RefineError> {
        let [r, _] = self
            .problem
            .build(
                self.pose,
                self.points,
                None,
                self.blocks,
                Parts::PointPose,
                None,
            )
            .ok_or(RefineError::Singular)?;
        self.system = (r.pose_pose, r.pose_gradient);
        Ok(self.cost)
    }

    #[inline(always)]
    fn solve_damped(&mut self, lambda: f64) -> bool {
        let (s, g) = &self.system;
        let mut damped = *s;
        for d in 0..6 {
            damped[(d, d)] *= 1.0 + lambda;
        }
        let Some(chol) = damped.cholesky() else {
            return false;
        };
        self.step = (-chol.solve(g), None);
        true
    }

    #[inline(always)]
    fn trial_cost(&mut self) -> f64 {
        let dxi = self.step.0;
        let next = moved(self.pose, &dxi);
        for ((t, p), b) in self
            .trial
            .iter_mut()
            .zip(self.points.iter())
            .zip(self.blocks.iter())
        {
            *t = back_substitute(p, &b.pp_inv, &(b.gradient + b.pose * dxi));
        }
        let c = self.problem.cost(&next, self.trial);
        self.step.1 = Some((next, c));
        c
    }

    #[inline(always)]
    fn converged(&self, current: f64, trial: f64) -> bool {
        (current - trial) < 1e-7 * current.max(1e-300) || self.step.0.norm() < 1e-10
    }

    #[inline(always)]
    fn accept(&mut self) {
        if let Some((next, c)) = self.step.1.take() {
            *self.pose = next;
            // The buffers swapped, not copied: `trial` is written whole before it is read.
            std::mem::swap(self.points, self.trial);
            self.cost = c;
        }
    }
}

/// Refines the motion `start` (`T_AB`, the pose of the current camera B in the reference
/// camera A) on the matched measurements `reference[i]` (in A) and `current[i]` (in B);
/// `folds[i]` (0 or 1) splits the matches into two halves whose normal equations are
/// returned separately (for held-out scoring of the disparity correction), all in fold 0
/// when `None`.
///
/// # Errors
/// [`RefineError::TooFewInliers`] when fewer than `min_inliers` matches are consistent;
/// [`RefineError::Singular`] for a degenerate configuration;
/// [`RefineError::LengthMismatch`] for slices of different lengths.
pub fn refine(
    model: &StereoModel,
    config: &RefineConfig,
    reference: &[StereoObservation],
    current: &[StereoObservation],
    folds: Option<&[u8]>,
    start: &Isometry3<f64>,
    min_inliers: usize,
) -> Result<Refined, RefineError> {
    if reference.len() != current.len() || folds.is_some_and(|f| f.len() != reference.len()) {
        return Err(RefineError::LengthMismatch {
            reference: reference.len(),
            current: current.len(),
        });
    }
    // Compiled for the CPU's best instruction set: the same IEEE operations (issue 34).
    dispatch(rounds::Refine {
        model,
        config,
        matches: (reference, current, folds),
        start,
        min_inliers,
    })
}

/// [`refine`] on slices of equal lengths, compiled into each instruction set's copy.
#[inline(always)]
fn refine_with(
    model: &StereoModel,
    config: &RefineConfig,
    (reference, current, folds): (&[StereoObservation], &[StereoObservation], Option<&[u8]>),
    start: &Isometry3<f64>,
    min_inliers: usize,
) -> Result<Refined, RefineError> {
    // The model's constants computed once, not per point (issue 34).
    let model = &Prepared::new(model);
    let mut pose = Pose::of(&start.inverse());
    // Points fitted to the starting pose, then gated.
    // A loop, not an iterator's map: compiled inside the dispatched copy.
    let mut fitted: Vec<Fitted> = Vec::with_capacity(reference.len());
    for (a, b) in reference.iter().zip(current) {
        let p = model.anchor(a);
        let finite = p.z > 0.0 && p.iter().all(|v| v.is_finite());
        fitted.push(if finite {
            fit_point(model, &pose, p, a, b)
        } else {
            None
        });
    }
    let mut problem = Problem {
        model,
        config,
        reference,
        current,
        active: Vec::new(),
    };
    // As large as every match: swapped with `trial`, neither needs more room.
    let mut points: Vec<Vector3<f64>> = Vec::with_capacity(fitted.len());
    let mut work = Work {
        blocks: Vec::with_capacity(fitted.len()),
        trial: Vec::with_capacity(fitted.len()),
    };
    let needed = min_inliers.max(3);
    let iterations =
        problem.gated_rounds(&mut pose, &mut fitted, &mut points, &mut work, needed)?;
    problem.result(pose, points, folds, iterations, work.blocks)
}

impl Problem<'_> {
    /// The refined motion at `pose` with the active matches' `points`: its covariance
    /// from the normal equations (per fold of `folds`), scaled by the residuals' and the
    /// regions' variance factors.
    #[inline(always)]
    fn result(
        self,
        pose: Pose,
        points: Vec<Vector3<f64>>,
        folds: Option<&[u8]>,
        iterations: usize,
        mut blocks: Vec<PoseBlocks>,
    ) -> Result<Refined, RefineError> {
        // The χ² and the scores from the same linearisation (issue 34: it was done twice).
        let mut sums = (0.0, Vec::with_capacity(points.len()));
        let reduced = self
            .build(
                &pose,
                &points,
                folds,
                &mut blocks,
                Parts::All,
                Some(&mut sums),
            )
            .ok_or(RefineError::Singular)?;
        let mut both = reduced[0];
        both += &reduced[1];
        let info = both.pose_pose;
        let inv = info.try_inverse().ok_or(RefineError::Singular)?;
        let n = self.active.len();
        let (chi2, mut scores) = sums;
        let dof = (3 * n).saturating_sub(6).max(1) as f64;
        let scale2 = chi2 / dof;
        let cluster_factor = noise::cluster_factor(&mut scores, &inv);
        Ok(Refined {
            motion: pose.isometry().inverse(),
            covariance: inv * noise::variance_factor(scale2, cluster_factor),
            inliers: self.active,
            points,
            scale2,
            cluster_factor,
            iterations,
            reduced,
        })
    }
}

/// A match's score on the pose with its point eliminated ([`noise::Score`]), at its
/// measurement `z` in B linearised as `lb` with the Huber weight `wb`, its point's
/// elimination blocks `b`.
#[inline(always)]
fn score(z: &StereoObservation, lb: &Linearized, wb: f64, b: &PoseBlocks) -> noise::Score {
    noise::Score {
        u: z.u,
        v: z.v,
        r: lb.d_pose.transpose() * lb.residual * wb - b.pose.transpose() * (b.pp_inv * b.gradient),
    }
}

#[cfg(test)]
mod floor_tests;
#[cfg(test)]
mod tests;
