//! The window's bundle adjustment: Levenberg-Marquardt on the keyframe poses, with the
//! points eliminated by their Schur complements.
//!
//! Each keyframe `k` has the pose `T_kw` (world to camera), perturbed as
//! `T_kw ← E(ξ_k) T_kw` with `E(ξ): P ↦ Exp(ω) P + ν`, `ξ = (ν, ω)` (metres, radians, in
//! camera `k`). A track anchored in keyframe `a` has the point `p = (x, y, ρ)` of
//! [`crate::refine::model`]; keyframe `j` sees it through `T_ja = T_jw T_aw⁻¹`, so with
//! `h = ρ P_j = R_ja (x, y, 1) + ρ t_ja`:
//!
//! ```text
//! ∂h/∂ξ_j = [ρ I, −[h]×],      ∂h/∂ξ_a = [−ρ R_ja, R_ja [(x, y, 1)]×]
//! ```
//!
//! (the first is the pair refinement's pose Jacobian, the second follows from
//! `T_ja ← T_ja E(ξ_a)⁻¹`). The oldest keyframe is held fixed. The reduced system
//! `S = H_ξξ − Σ_points H_ξp H_pp⁻¹ H_pξ` is dense, `6 (K − 1)` square, and solved by
//! Cholesky with Levenberg-Marquardt damping; points follow by back-substitution.

use nalgebra::allocator::Allocator;
use nalgebra::{
    DMatrix, DVector, DefaultAllocator, Dim, Dyn, Matrix3, Matrix6, OMatrix, Vector3, Vector6,
};

mod system;

use super::prior::{Prior, terms};
use super::residual::{Relative, relative_poses};
use super::tracks::{Tracks, tracks_of};
use super::{Keyframe, WindowConfig, WindowReport};
use crate::nls::lm::{Damping, LeastSquares};
use crate::nls::pose::Pose;
use crate::nls::products::{mul, mul_vec, tr_mul};
use crate::nls::robust::huber;
use crate::nls::schur::back_substitute;
use crate::refine::Prepared;
use crate::refine::evidence::{Matrix6xK, MatrixK, VectorK};
use crate::refine::model::{Matrix3x6, StereoModel};
use crate::refine::noise::{Score, cluster_factor, variance_factor};
use swarmpose_vision::simd::{Kernel, dispatch};
use system::{Blocks, build};

/// Robust cost `Σ ρ` of every track at the relative poses `rel` of `n` keyframes, or
/// infinity when a point leaves a view.
#[inline(always)]
fn cost(
    model: &StereoModel,
    k: f64,
    (rel, n): (&[Relative], usize),
    tracks: &Tracks,
    points: &[Vector3<f64>],
) -> f64 {
    // The model's constants once, not per measurement (the same bits).
    let model = &Prepared::new(model);
    let mut total = 0.0;
    for ((_, obs), p) in tracks.iter().zip(points) {
        let anchor = obs[0].0;
        for (slot, z) in obs {
            let r2 = if *slot == anchor {
                model.residual2_in_reference(p, z)
            } else {
                let (rot, trans) = &rel[slot * n + anchor];
                match model.residual2_in_current(rot, trans, p, z) {
                    Some(r2) => r2,
                    None => return f64::INFINITY,
                }
            };
            total += huber(r2, k).1;
        }
    }
    total
}

/// The blocks of one track kept for back-substitution; its `H_pξ` blocks are
/// `Scratch::hpx[start..end]`.
#[derive(Debug, Clone)]
struct Eliminated {
    hpp_inv: Matrix3<f64>,
    gp: Vector3<f64>,
    start: usize,
    end: usize,
}

/// Buffers of one refinement, reused over its iterations (and, in the window's
/// [`Workspace`], from frame to frame).
#[derive(Debug, Clone, Default)]
pub(super) struct Scratch {
    pub(super) rel: Vec<Relative>,
    elim: Vec<Eliminated>,
    /// `H_pξ` per track and pose variable (index of the variable, 3x6 block).
    hpx: Vec<(usize, Matrix3x6)>,
    /// The track's direct part of the score of the same pose variable as `hpx` (its
    /// measurements' `J_ξᵀ W e`), for the clustered noise scale ([`newest_covariance`]).
    hgx: Vec<Vector6<f64>>,
    /// The reduced system's 6x6 blocks, row-major over the pose variables.
    blocks: Vec<Matrix6<f64>>,
    gradient: Vec<Vector6<f64>>,
    /// `Σ w r²` of the last build (Huber-weighted squared whitened residuals).
    chi2: f64,
    /// The robust cost `Σ ρ` at the last build's linearisation point.
    cost: f64,
    /// The reduced system's pose-by-calibration blocks `S_ξc` (points eliminated), one
    /// per pose variable: how the calibration terms pull on each pose.
    pub(super) pose_calibration: Vec<Matrix6xK>,
    /// The reduced system of the last build: `S` and the gradient `g`.
    s: DMatrix<f64>,
    g: DVector<f64>,
}

/// `dst = src`, in `dst`'s buffer when it has the size.
fn assign<C: Dim>(dst: &mut OMatrix<f64, Dyn, C>, src: &OMatrix<f64, Dyn, C>)
where
    DefaultAllocator: Allocator<Dyn, C>,
{
    if dst.shape() == src.shape() {
        dst.copy_from(src);
    } else {
        *dst = src.clone();
    }
}

/// The linearised system of `tracks` (from [`tracks_of`]) over every pose of `poses`,
/// none held fixed, the points eliminated: the information `S` (`6 n` square) and the
/// gradient `g` of half the robust cost. `None` if a point left a view or its block is
/// singular.
pub(super) fn linearised_system(
    model: &StereoModel,
    k: f64,
    poses: &[Pose],
    tracks: &Tracks,
    sc: &mut Scratch,
) -> Option<(DMatrix<f64>, DVector<f64>)> {
    let points: Vec<Vector3<f64>> = tracks.list.iter().map(|t| t.point).collect();
    build(model, k, (poses, 0, Blocks::Full), tracks, &points, sc)?;
    Some((std::mem::take(&mut sc.s), std::mem::take(&mut sc.g)))
}

/// The buffers of the window's refinement, kept from frame to frame: their sizes follow
/// the window's contents, which are bounded.
#[derive(Debug, Clone, Default)]
pub(crate) struct Workspace {
    sc: Scratch,
    tracks: Tracks,
    poses: Vec<Pose>,
    trial: Vec<Pose>,
    points: Vec<Vector3<f64>>,
    trial_points: Vec<Vector3<f64>>,
    trial_rel: Vec<Relative>,
    /// The damped system, factorised in place.
    damped: DMatrix<f64>,
    dx: DVector<f64>,
    /// The newest pose's columns of `S⁻¹` ([`newest_covariance`]).
    columns: DMatrix<f64>,
    /// The tracks' pulls on the newest pose ([`track_scores`]).
    scores: Vec<Score>,
}

impl Workspace {
    /// Heap bytes held.
    pub(crate) fn heap_bytes(&self) -> usize {
        let sc = &self.sc;
        sc.rel.capacity() * size_of::<Relative>()
            + sc.elim.capacity() * size_of::<Eliminated>()
            + sc.hpx.capacity() * size_of::<(usize, Matrix3x6)>()
            + sc.hgx.capacity() * size_of::<Vector6<f64>>()
            + sc.blocks.capacity() * size_of::<Matrix6<f64>>()
            + sc.gradient.capacity() * size_of::<Vector6<f64>>()
            + sc.pose_calibration.capacity() * size_of::<Matrix6xK>()
            + (sc.s.len() + sc.g.len() + self.damped.len() + self.dx.len() + self.columns.len())
                * size_of::<f64>()
            + self.tracks.heap_bytes()
            + (self.poses.capacity() + self.trial.capacity()) * size_of::<Pose>()
            + (self.points.capacity() + self.trial_points.capacity()) * size_of::<Vector3<f64>>()
            + self.trial_rel.capacity() * size_of::<Relative>()
            + self.scores.capacity() * size_of::<Score>()
    }
}

/// Refines the window's poses (all but the oldest) and its tracks' points in place, with
/// the `prior` of the keyframes marginalised before when there is one (ignored when one
/// of its keyframes is not in `frames`). `None` when there is nothing to refine or the
/// system is singular (poses unchanged).
/// Compiled for the CPU's best instruction set ([`dispatch`]): the same IEEE operations in
/// the same order, fewer instructions (issue 34).
pub(crate) fn refine_window(
    model: &StereoModel,
    calibration_covariance: &MatrixK,
    config: &WindowConfig,
    frames: &mut [Keyframe],
    prior: Option<&Prior>,
    ws: &mut Workspace,
) -> Option<WindowReport> {
    dispatch(RefineWindow {
        model,
        calibration_covariance,
        config,
        frames,
        prior,
        ws,
    })
}

/// A call of [`refine_window`] for [`dispatch`].
struct RefineWindow<'a> {
    model: &'a StereoModel,
    calibration_covariance: &'a MatrixK,
    config: &'a WindowConfig,
    frames: &'a mut [Keyframe],
    prior: Option<&'a Prior>,
    ws: &'a mut Workspace,
}

impl Kernel for RefineWindow<'_> {
    type Output = Option<WindowReport>;

    #[inline(always)]
    fn run(self) -> Option<WindowReport> {
        let c = (self.calibration_covariance, self.config);
        refine_window_with(self.model, c, self.frames, self.prior, self.ws)
    }
}

/// [`refine_window`]'s body, compiled into each instruction set's copy.
#[inline(always)]
fn refine_window_with(
    model: &StereoModel,
    (calibration_covariance, config): (&MatrixK, &WindowConfig),
    frames: &mut [Keyframe],
    prior: Option<&Prior>,
    ws: &mut Workspace,
) -> Option<WindowReport> {
    if frames.len() < 2 {
        return None;
    }
    let k = config.huber_k;
    ws.poses.clear();
    ws.poses.extend(frames.iter().map(|f| Pose::of(&f.pose_cw)));
    let n = ws.poses.len();
    let (sc, tracks) = (&mut ws.sc, &mut ws.tracks);
    tracks_of(model, k, frames, &ws.poses, |_| true, &mut sc.rel, tracks);
    let observations = ws.tracks.observations();
    ws.points.clear();
    ws.points.extend(ws.tracks.list.iter().map(|t| t.point));
    if ws.tracks.is_empty() {
        return None;
    }
    ws.trial_points.clear();
    ws.trial_points.extend_from_slice(&ws.points);
    let mut lm = WindowLm {
        ws,
        model,
        k,
        n,
        // The prior of the keyframes marginalised before, on the slots of its keyframes.
        prior: prior.and_then(|p| p.on(frames).map(|slots| (p, slots))),
        terms: terms(model),
        observations,
        calibration_covariance,
        iterations: 0,
        covariance: None,
    };
    let iterations = WINDOW_DAMPING
        .minimise(&mut lm, config.max_iterations)
        .ok()?;
    let (ws, covariance) = (lm.ws, lm.covariance);
    for (f, p) in frames.iter_mut().zip(ws.poses.iter()) {
        f.pose_cw = p.isometry();
    }
    Some(WindowReport {
        keyframes: frames.len(),
        tracks: ws.tracks.len(),
        observations,
        iterations,
        keyframe: frames.last().is_some_and(|f| f.keyframe),
        covariance,
    })
}

/// The damping of the window: from 10⁻⁴, a step still tried at 10⁸.
const WINDOW_DAMPING: Damping = Damping {
    start: 1e-4,
    ceiling: 1e8,
    ceiling_tried: true,
};

/// The window's Levenberg-Marquardt problem: the state and buffers in the workspace, the
/// prior of the keyframes marginalised before, and the covariance of the newest pose,
/// taken at the first linearisation.
struct WindowLm<'w> {
    ws: &'w mut Workspace,
    model: &'w StereoModel,
    /// Huber threshold.
    k: f64,
    /// Keyframes.
    n: usize,
    prior: Option<(&'w Prior, Vec<usize>)>,
    /// The calibration terms the prior is evaluated at.
    terms: VectorK,
    observations: usize,
    calibration_covariance: &'w MatrixK,
    iterations: usize,
    covariance: Option<Matrix6<f64>>,
}

impl WindowLm<'_> {
    /// The prior's part of the cost at `poses`.
    #[inline(always)]
    fn prior_energy(&self, poses: &[Pose]) -> f64 {
        self.prior
            .as_ref()
            .map_or(0.0, |(p, slots)| p.energy(slots, poses, &self.terms))
    }
}

impl LeastSquares for WindowLm<'_> {
    /// The window's system cannot be built (a point left a view, a singular block) or
    /// its cost is not finite.
    type Error = ();

    #[inline(always)]
    fn linearise(&mut self) -> Result<f64, ()> {
        self.iterations += 1;
        let Self { ws, model, k, .. } = self;
        // The cost at the current state comes with its linearisation. Both factorisations
        // of `S` (the step's, the covariance's) read its lower triangle only.
        let sc = &mut ws.sc;
        let poses = (&ws.poses[..], 1, Blocks::Lower);
        build(model, *k, poses, &ws.tracks, &ws.points, sc).ok_or(())?;
        if let Some((p, slots)) = &self.prior {
            let system = (&mut sc.s, &mut sc.g);
            p.add_to(
                (slots, &ws.poses, 1),
                &self.terms,
                system,
                &mut sc.pose_calibration,
            );
        }
        let current = sc.cost + self.prior_energy(&self.ws.poses);
        if !current.is_finite() {
            return Err(());
        }
        if self.iterations == 1 {
            let ws = &mut *self.ws;
            self.covariance = newest_covariance(
                &ws.sc,
                (self.observations, &ws.tracks),
                self.calibration_covariance,
                (&mut ws.damped, &mut ws.columns, &mut ws.scores),
            );
        }
        Ok(current)
    }

    #[inline(always)]
    fn solve_damped(&mut self, lambda: f64) -> bool {
        self.ws.solve_damped(lambda)
    }

    #[inline(always)]
    fn trial_cost(&mut self) -> f64 {
        self.ws.move_trial();
        let ws = &*self.ws;
        cost(
            self.model,
            self.k,
            (&ws.trial_rel, self.n),
            &ws.tracks,
            &ws.trial_points,
        ) + self.prior_energy(&ws.trial)
    }

    #[inline(always)]
    fn converged(&self, current: f64, trial: f64) -> bool {
        current - trial < 1e-6 * current
    }

    #[inline(always)]
    fn accept(&mut self) {
        let ws = &mut *self.ws;
        std::mem::swap(&mut ws.poses, &mut ws.trial);
        ws.points.copy_from_slice(&ws.trial_points);
    }
}

impl Workspace {
    /// The step `dx` of the reduced system damped by `lambda` (`S + λ diag(S)`, and a
    /// tiny constant on the diagonal); false when that is not positive definite.
    #[inline(always)]
    fn solve_damped(&mut self, lambda: f64) -> bool {
        let Self { sc, damped, dx, .. } = self;
        assign(damped, &sc.s);
        for d in 0..damped.nrows() {
            damped[(d, d)] *= 1.0 + lambda;
            damped[(d, d)] += 1e-12;
        }
        // Factorised in its own buffer, which is taken back after the solve.
        let Some(chol) = std::mem::take(damped).cholesky() else {
            return false;
        };
        assign(dx, &sc.g);
        chol.solve_mut(dx);
        dx.neg_mut();
        *damped = chol.unpack_dirty();
        true
    }

    /// The state moved by the step `dx` into `trial` (every pose but the oldest),
    /// `trial_points` (each point back-substituted) and `trial_rel`.
    #[inline(always)]
    fn move_trial(&mut self) {
        let Self {
            sc,
            poses,
            trial,
            points,
            trial_points,
            trial_rel,
            dx,
            ..
        } = self;
        trial.clear();
        trial.extend_from_slice(poses);
        for (v, pose) in trial.iter_mut().enumerate().skip(1) {
            let o = 6 * (v - 1);
            let nu = Vector3::new(dx[o], dx[o + 1], dx[o + 2]);
            let om = Vector3::new(dx[o + 3], dx[o + 4], dx[o + 5]);
            *pose = pose.moved(&nu, &om);
        }
        for ((tp, p), e) in trial_points.iter_mut().zip(points.iter()).zip(&sc.elim) {
            let mut rhs = e.gp;
            for (v, b) in &sc.hpx[e.start..e.end] {
                // nalgebra's `b * dx.fixed_rows::<6>(6 v)` bit for bit ([`mul_vec`]).
                let x: [f64; 6] = std::array::from_fn(|k| dx[6 * v + k]);
                rhs += mul_vec(b, &x);
            }
            *tp = back_substitute(p, &e.hpp_inv, &rhs);
        }
        relative_poses(trial, trial_rel);
    }
}

/// The covariance of the newest keyframe's pose perturbation `ξ` (the oldest held fixed)
/// at the start of the refinement. The measurements' part is the newest pose's block of
/// `S⁻¹`, `S` the reduced information (points eliminated), scaled by the larger of the
/// residuals' variance factor `χ² / dof` with `dof = 3 (observations − tracks) − rows of
/// S` (1 when the pixel noise is as modelled) and the regions' factor
/// ([`cluster_factor`]) of the tracks' pulls on the newest pose, each track's
/// measurements in every keyframe summed before they are squared: a track seen again in
/// more frames with the same error (the same pixels, the same texture) adds nothing to
/// the confidence, where the residuals' factor would count every sighting as new
/// evidence. The calibration's part:
/// the solution moves with the calibration terms `c` as `∂ξ/∂c = −S⁻¹ S_ξc`, so their
/// covariance `Σ_c` adds `G Σ_c Gᵀ` with `G` the newest pose's rows of `S⁻¹ S_ξc`.
/// `None` when `S` is not positive definite. `factor`, `columns` and `scores` are buffers.
#[inline(always)]
fn newest_covariance(
    sc: &Scratch,
    (observations, tracks): (usize, &Tracks),
    calibration_covariance: &MatrixK,
    (factor, columns, scores): (&mut DMatrix<f64>, &mut DMatrix<f64>, &mut Vec<Score>),
) -> Option<Matrix6<f64>> {
    let (s, pose_calibration) = (&sc.s, &sc.pose_calibration);
    let n = s.nrows();
    if n < 6 || pose_calibration.len() * 6 != n {
        return None;
    }
    let dof = (3 * observations).checked_sub(3 * tracks.len() + n)?.max(1) as f64;
    assign(factor, s);
    let chol = std::mem::take(factor).cholesky()?;
    if columns.shape() == (n, 6) {
        columns.fill(0.0);
    } else {
        *columns = DMatrix::zeros(n, 6);
    }
    for i in 0..6 {
        columns[(n - 6 + i, i)] = 1.0;
    }
    // The newest pose's columns of S⁻¹ (its rows, S being symmetric).
    chol.solve_mut(columns);
    *factor = chol.unpack_dirty();
    let block: Matrix6<f64> = columns.fixed_view::<6, 6>(n - 6, 0).into_owned();
    let block = (block + block.transpose()) * 0.5;
    let classic = sc.chi2 / dof;
    // A match, not a closure: the scores are compiled inside the dispatched copy.
    let cluster = match block.try_inverse() {
        Some(info) => {
            track_scores(sc, tracks, columns, scores);
            cluster_factor(scores, &info)
        }
        None => None,
    };
    let mut cov = block * variance_factor(classic, cluster);
    let mut g = Matrix6xK::zeros();
    for (v, sxc) in pose_calibration.iter().enumerate() {
        g += columns.fixed_view::<6, 6>(6 * v, 0).transpose() * sxc;
    }
    let from_calibration = g * calibration_covariance * g.transpose();
    cov += (from_calibration + from_calibration.transpose()) * 0.5;
    cov.iter().all(|v| v.is_finite()).then_some(cov)
}

/// Each track's pull on the newest pose, `(S⁻¹ r_t)` of the newest pose (`columns`, its
/// columns of `S⁻¹`), `r_t` the track's score over every free pose with its point
/// eliminated, all its measurements in the window together: at the track's position in
/// its anchor keyframe; into `scores`, a buffer kept from frame to frame (issue 34).
// A loop, not an iterator's map: compiled inside the dispatched copy.
#[inline(always)]
fn track_scores(sc: &Scratch, tracks: &Tracks, columns: &DMatrix<f64>, scores: &mut Vec<Score>) {
    scores.clear();
    for ((_, obs), e) in tracks.iter().zip(&sc.elim) {
        let mut g = Vector6::zeros();
        // nalgebra's products bit for bit, without its generic ones ([`mul`], [`tr_mul`],
        // [`mul_vec`]); `H_pp⁻¹ g_p` once per track.
        let through = mul(&e.hpp_inv, &e.gp);
        for i in e.start..e.end {
            let (v, hpx) = &sc.hpx[i];
            let r = sc.hgx[i] - tr_mul(hpx, &through);
            let c: Matrix6<f64> = columns.fixed_view::<6, 6>(6 * v, 0).transpose();
            g += mul_vec(&c, &r.data.0[0]);
        }
        let z = obs[0].1;
        scores.push(Score {
            u: z.u,
            v: z.v,
            r: g,
        });
    }
}

#[cfg(test)]
mod tests;
