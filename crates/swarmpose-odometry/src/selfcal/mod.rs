//! Self-calibration of the disparity correction by evidence, online.
//!
//! A stereo rig whose right principal point, focal length or orientation is slightly off
//! in its calibration measures every disparity short by `δ(x, y)` pixels
//! ([`DisparityCorrection`]: a constant for a principal point, `f ψ (1 + x²)` for a yaw
//! `ψ` of the right camera, and terms in `x`, `y`, `x y`). Such an error bends the
//! triangulated scene, so the same points seen from two places no longer fit one rigid
//! motion: the reprojection cost of a moving pair depends on `δ`. A pair without
//! translation says nothing about it: its information is 0. A pair whose features moved
//! by less than a pixel adds no rigidity evidence at all (the tracker's
//! `MIN_EVIDENCE_FLOW_PX`): there the front end's own sub-pixel errors are as large as
//! the motion and bend the pair like a disparity offset.
//!
//! **Two kinds of evidence.** A rotation of the right camera also moves its image points
//! vertically, which every stereo match measures directly, frame by frame and without
//! any motion ([`rows`]): the yaw, roll and pitch terms come from there. A principal
//! point (or focal length) error of the right camera moves points only horizontally and
//! is seen only as a scene that is not rigid between two places, below.
//!
//! **Rigidity.** The refinement of every tracked pair returns its normal equations with
//! the points eliminated ([`crate::refine::evidence`]). Eliminating the pose as well gives
//! a quadratic model of the pair's *profile* cost in the coefficients `c` (the pose re-optimised
//! for each `c`), in χ² units (divided by the pair's residual variance factor). Summed
//! over the pairs so far, it is a fixed-size state: memory does not grow with the
//! sequence. The matches are split into two folds by alternate vertical stripes of the
//! image (16 stripes, so invariant to the image size), each with its own profile.
//!
//! **Decision.** A model is a set of causes ([`CorrectionModel`]). The rows choose the
//! rotation terms ([`rows::RowEvidence::decide`]); on top of them, the rigidity evidence
//! chooses the horizontal terms: each candidate is fitted on one fold and scored on the
//! other (both ways), the held-out score `S_M = Q₀(ĉ_M¹) + Q₁(ĉ_M⁰)` in χ² units relative
//! to the rotation terms alone. In both, forward selection adds one term at a time while
//! it lowers the held-out score by more than [`SelfCalConfig::margin`]. With an exact
//! calibration the fitted corrections only fit noise and score worse on the other fold,
//! so none is chosen (the false-alarm rate of the margin is measured in the tests). Terms
//! chosen by a hair are applied by a fraction ([`applied_fraction`]), so that the
//! correction does not jump as the score crosses the margin. The
//! rows' yaw is a hypothesis that rigidity checks: the `x y` term of the rows can come
//! from something other than a yaw (on kitti_vo_seq2 the rows say `f ψ = −5.6 px`, a
//! correction that rigidity rejects), so it is kept only when a quadratic term fitted by
//! rigidity alone does not score better, by the margin, on the held-out folds (scores
//! relative to no correction at all). The correction applied is the chosen model fitted
//! on the evidence so far; it is re-decided after every frame, so it uses the frames
//! that have arrived and never later ones.
//!
//! **Evidence that fades.** A pair's evidence is computed under the correction in use
//! when it arrived, and leans towards it (its inliers are gated and weighted under it).
//! So a pair is refined again under the correction its own evidence leads to, until the
//! two agree (at most 4 times, only while the correction still moves), and the evidence
//! of past pairs fades with a time constant of [`SelfCalConfig::memory_s`] seconds.

mod causes;
pub mod rows;

pub use causes::CorrectionModel;

use nalgebra::SMatrix;
use swarmpose_vision::frontend::{CORRECTION_TERMS, DisparityCorrection};
use swarmpose_vision::stereo::RectifiedStereo;

use crate::refine::evidence::{MatrixK, QuadraticCost, Reduced, VectorK};
use crate::refine::model::FOCAL_TERM;
use rows::{RowDecision, RowEvidence};

const K: usize = crate::refine::model::CALIBRATION_TERMS;

/// Settings of the self-calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SelfCalConfig {
    /// How much lower, in χ² units, the held-out score must become for a term to be
    /// added to the correction (default 10; the false-alarm rate on exact rigs is
    /// measured in the tests).
    pub margin: f64,
    /// Number of vertical image stripes that alternate between the two folds
    /// (default 16).
    pub stripes: usize,
    /// The causes the selection may use (default [`CorrectionModel::DEFAULT_CANDIDATES`]).
    pub candidates: CorrectionModel,
    /// Largest standard error, pixels, with which each fold must determine a term of the
    /// rigidity evidence before the term is considered (default 0.5): a camera that does
    /// not move says nothing about a principal point, and a fit on nothing could pass
    /// any margin.
    pub max_sigma_px: f64,
    /// Largest relative standard error with which each fold must determine the focal
    /// length of the rig before [`CorrectionModel::FOCAL_LENGTH`] is considered
    /// (default 0.005, 0.5 %: 3.5 px of a 700 px focal length; unit-free, so the
    /// same for any image size).
    pub max_focal_sigma: f64,
    /// Time constant, seconds, with which the rigidity evidence of past pairs fades
    /// (default 1.0; `f64::INFINITY` keeps all of it). A pair's evidence is computed
    /// under the correction in use when it arrived (its inliers are gated and weighted
    /// under it) and leans towards that correction: on the Karlsruhe sequence the whole
    /// sequence's constant offset, with every pair computed under 0, 0.7, 1.4 and
    /// 2.1 px, comes out 0.51, 0.83, 1.08 and 1.23 px (kitti_vo_seq2: 0.98, 1.17, 1.28,
    /// 1.34 px). Evidence gathered under corrections since replaced must fade so that
    /// the estimate can reach the correction its own evidence confirms. In seconds, so
    /// that the memory does not depend on the frame rate. RESULTS.md gives the effect
    /// of other values on every sequence.
    pub memory_s: f64,
}

impl Default for SelfCalConfig {
    fn default() -> Self {
        Self {
            margin: 10.0,
            stripes: 16,
            candidates: CorrectionModel::DEFAULT_CANDIDATES,
            max_sigma_px: 0.5,
            max_focal_sigma: 0.005,
            memory_s: 1.0,
        }
    }
}

/// The horizontal causes, seen by rigidity, and their coefficient index.
const RIGID_CAUSES: [(CorrectionModel, usize); 3] = [
    (CorrectionModel::PRINCIPAL_POINT, 0),
    (CorrectionModel::FOCAL, 2),
    (CorrectionModel::FOCAL_LENGTH, FOCAL_TERM),
];

/// The horizontal causes with the `x²` term fitted by rigidity alone (a yaw that the
/// rows do not show, or something else that bends disparities towards the edges).
const RIGID_CAUSES_WITH_YAW: [(CorrectionModel, usize); 4] = [
    (CorrectionModel::PRINCIPAL_POINT, 0),
    (CorrectionModel::YAW, 1),
    (CorrectionModel::FOCAL, 2),
    (CorrectionModel::FOCAL_LENGTH, FOCAL_TERM),
];

/// The minimiser of `q` over `base + Σ z_k e_k` for the coefficients `free`.
fn fit_on_base(q: &QuadraticCost, base: &VectorK, free: &[usize]) -> VectorK {
    let n = free.len();
    let mut out = *base;
    if n == 0 {
        return out;
    }
    let rhs = q.b - q.a * base;
    let mut a = SMatrix::<f64, K, K>::identity();
    let mut b = VectorK::zeros();
    for (i, &ki) in free.iter().enumerate() {
        b[i] = rhs[ki];
        for (j, &kj) in free.iter().enumerate() {
            a[(i, j)] = q.a[(ki, kj)];
        }
    }
    let scale = (0..n).map(|i| a[(i, i)].abs()).fold(0.0, f64::max);
    if scale <= 0.0 {
        return out;
    }
    for i in 0..n {
        a[(i, i)] += 1e-12 * scale;
    }
    if let Some(chol) = a.cholesky() {
        let z = chol.solve(&b);
        for (i, &ki) in free.iter().enumerate() {
            out[ki] += z[i];
        }
    }
    out
}

/// The covariance of the coefficients `free` fitted on `q` (`A⁻¹` over them, χ² units so
/// pixels²), zero elsewhere; zero when `A` is singular there.
fn covariance_on(q: &QuadraticCost, free: &[usize]) -> MatrixK {
    let n = free.len();
    let mut out = MatrixK::zeros();
    if n == 0 {
        return out;
    }
    let mut a = SMatrix::<f64, K, K>::identity();
    for (i, &ki) in free.iter().enumerate() {
        for (j, &kj) in free.iter().enumerate() {
            a[(i, j)] = q.a[(ki, kj)];
        }
    }
    let Some(chol) = a.cholesky() else {
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
fn rows_covariance(rows: &RowDecision) -> MatrixK {
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

/// The current decision and its evidence.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Decision {
    /// The causes chosen.
    pub model: CorrectionModel,
    /// The correction applied: the chosen causes fitted on all the evidence so far.
    pub correction: DisparityCorrection,
    /// The change of the rig's focal length applied, pixels of `fx` (`fy` in proportion;
    /// 0 unless [`CorrectionModel::FOCAL_LENGTH`] is chosen).
    pub focal_px: f64,
    /// What the rows say about the right camera's rotation.
    pub rows: RowDecision,
    /// Held-out rigidity score of the horizontal terms chosen, χ² units relative to the
    /// rotation terms alone (lower is better; 0 when none is chosen).
    pub rigidity_score: f64,
    /// Held-out rigidity score of the best horizontal term not chosen (the margin it
    /// missed), or `None` when none is left.
    pub rigidity_next_score: Option<f64>,
    /// Fraction of the horizontal terms' fitted values that is applied (0 to 1):
    /// [`applied_fraction`] of the held-out score; 0 when none is chosen.
    pub rigidity_weight: f64,
    /// Covariance of the calibration terms applied (disparity correction coefficients,
    /// then the focal length; pixels²): the inverse of the rigidity evidence's
    /// information over the terms it fitted, plus the row fit's covariance of the
    /// rotation terms read off the rows (mapped to the coefficients they set; the two are
    /// taken as independent). Zero when no term is applied.
    pub covariance: MatrixK,
    /// Pairs that contributed rigidity evidence.
    pub pairs: usize,
    /// Frames whose confirmed matches gave row evidence.
    pub frames: usize,
}

fn correction_of(c: &VectorK) -> DisparityCorrection {
    let mut a = [0.0; CORRECTION_TERMS];
    a.copy_from_slice(&c.as_slice()[..CORRECTION_TERMS]);
    DisparityCorrection::from_coefficients(a)
}

/// The calibration vector of a disparity correction and a focal length change (pixels).
fn vector_of(c: &DisparityCorrection, focal_px: f64) -> VectorK {
    let mut v = VectorK::zeros();
    for (k, a) in c.coefficients().iter().enumerate() {
        v[k] = *a;
    }
    v[FOCAL_TERM] = focal_px;
    v
}

/// The online self-calibration: evidence accumulated over frames and pairs (fixed size),
/// and the decision.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct SelfCalibration {
    config: SelfCalConfig,
    rows: RowEvidence,
    joint: QuadraticCost,
    folds: [QuadraticCost; 2],
    decision: Decision,
    /// The calibration's focal length `fx`, pixels (from [`SelfCalibration::add_rows`]).
    focal_px: f64,
}

impl SelfCalibration {
    /// No evidence yet: no correction.
    #[must_use]
    pub fn new(config: SelfCalConfig) -> Self {
        Self {
            config,
            ..Self::default()
        }
    }

    /// The current decision.
    #[must_use]
    pub fn decision(&self) -> &Decision {
        &self.decision
    }

    /// Adds the row offsets `(u, v, d, dy)` (pixels) of the stereo matches of one frame
    /// that a tracked motion confirmed; the decision is updated by the next
    /// [`SelfCalibration::add_pair`].
    pub fn add_rows(
        &mut self,
        samples: impl IntoIterator<Item = (f64, f64, f64, f32)>,
        rig: &RectifiedStereo,
        image_width: usize,
    ) {
        self.focal_px = rig.fx;
        let rotation = CorrectionModel::YAW
            .with(CorrectionModel::ROLL)
            .with(CorrectionModel::PITCH);
        if self.config.candidates.0 & rotation.0 != 0 {
            let stripe = (image_width as f64 / self.config.stripes.max(1) as f64).max(1.0);
            self.rows.add(samples, rig, stripe);
        }
        self.decision.frames += 1;
    }

    /// Adds the evidence of one refined pair: its reduced normal equations per fold,
    /// computed with the correction `at` and the focal length changed by `focal_px`, and its residual variance factor `scale2`;
    /// `dt_s` (seconds since the previous pair) fades the evidence so far by
    /// `exp(−dt_s / memory_s)` ([`SelfCalConfig::memory_s`]). Returns the updated
    /// decision.
    pub fn add_pair(
        &mut self,
        reduced: &[Reduced; 2],
        at: &DisparityCorrection,
        focal_px: f64,
        scale2: f64,
        dt_s: f64,
    ) -> &Decision {
        if !(scale2.is_finite() && scale2 > 0.0) {
            return &self.decision;
        }
        self.fade(dt_s);
        let at = vector_of(at, focal_px);
        let mut both = reduced[0];
        both += &reduced[1];
        let Some((info, grad)) = both.profile() else {
            return &self.decision;
        };
        if !finite(&info, &grad) {
            return &self.decision;
        }
        self.joint.add(&info, &grad, &at, scale2);
        for (fold, r) in self.folds.iter_mut().zip(reduced) {
            if let Some((info, grad)) = r.profile()
                && finite(&info, &grad)
            {
                fold.add(&info, &grad, &at, scale2);
            }
        }
        self.decision.pairs += 1;
        self.decide();
        &self.decision
    }

    /// A pair that adds no rigidity evidence (it moved too little to say anything about
    /// the calibration), `dt_s` seconds after its reference: the evidence so far fades
    /// over that time, and the decision is taken again (the rows may have changed).
    pub fn add_pair_without_evidence(&mut self, dt_s: f64) -> &Decision {
        self.fade(dt_s);
        self.decide();
        &self.decision
    }

    /// Fades the rigidity evidence over `dt_s` seconds (the time constant
    /// [`SelfCalConfig::memory_s`]).
    fn fade(&mut self, dt_s: f64) {
        let keep = (-dt_s.max(0.0) / self.config.memory_s).exp();
        if keep.is_finite() && keep < 1.0 {
            for q in std::iter::once(&mut self.joint).chain(self.folds.iter_mut()) {
                q.scale(keep);
            }
        }
    }

    fn decide(&mut self) {
        let c = self.config;
        let mut rows = self.rows.decide(c.margin);
        rows.yaw &= c.candidates.has(CorrectionModel::YAW);
        rows.roll &= c.candidates.has(CorrectionModel::ROLL);
        rows.pitch &= c.candidates.has(CorrectionModel::PITCH);
        // With the rows' rotation terms as they are, the horizontal terms by rigidity.
        let mut chosen = self.select(&rows, &RIGID_CAUSES);
        if rows.yaw {
            // The rows' x y term need not be a yaw (a rectification left with some
            // distortion bends the rows too): their yaw is kept only if rigidity does
            // not prefer its own x² term by the margin.
            let mut no_yaw = rows;
            no_yaw.yaw = false;
            let own = self.select(&no_yaw, &RIGID_CAUSES_WITH_YAW);
            if own.model.has(CorrectionModel::YAW) && own.absolute < chosen.absolute - c.margin {
                chosen = own;
                rows.yaw = false;
            }
        }
        let weight = applied_fraction(chosen.relative, chosen.free.len(), c.margin);
        let fitted = fit_on_base(&self.joint, &chosen.base, &chosen.free);
        let fitted = chosen.base + (fitted - chosen.base) * weight;
        self.decision = Decision {
            model: chosen.model,
            correction: correction_of(&fitted),
            focal_px: fitted[FOCAL_TERM],
            covariance: covariance_on(&self.joint, &chosen.free) + rows_covariance(&rows),
            rows,
            rigidity_score: chosen.relative,
            rigidity_next_score: chosen.next,
            rigidity_weight: weight,
            pairs: self.decision.pairs,
            frames: self.decision.frames,
        };
    }

    /// Forward selection of the horizontal terms among `causes`, by held-out rigidity, on
    /// top of the rotation terms that `rows` supports.
    fn select(&self, rows: &RowDecision, causes: &[(CorrectionModel, usize)]) -> Selection {
        let c = &self.config;
        let mut model = CorrectionModel::NONE;
        for (flag, on) in [
            (CorrectionModel::YAW, rows.yaw),
            (CorrectionModel::ROLL, rows.roll),
            (CorrectionModel::PITCH, rows.pitch),
        ] {
            if on {
                model = model.with(flag);
            }
        }
        let base = vector_of(&rows.correction(), 0.0);
        let [f0, f1] = &self.folds;
        let zero = VectorK::zeros();
        // Held-out score of the base itself, relative to no correction.
        let base_score = f0.value(&base) + f1.value(&base) - f0.value(&zero) - f1.value(&zero);
        let score = |free: &[usize]| {
            f0.value(&fit_on_base(f1, &base, free)) + f1.value(&fit_on_base(f0, &base, free))
                - f0.value(&base)
                - f1.value(&base)
        };
        let determined = |k: usize| {
            // The focal length's standard error relative to the focal length.
            let sigma = if k == FOCAL_TERM {
                c.max_focal_sigma * self.focal_px
            } else {
                c.max_sigma_px
            };
            self.folds
                .iter()
                .all(|f| f.a[(k, k)] * sigma * sigma >= 1.0)
        };
        let mut free: Vec<usize> = Vec::new();
        let mut best = 0.0;
        let next = loop {
            let candidate = causes
                .iter()
                .filter(|(cause, k)| {
                    c.candidates.has(*cause) && !free.contains(k) && determined(*k)
                })
                .map(|&(cause, k)| {
                    let mut f = free.clone();
                    f.push(k);
                    (cause, k, score(&f))
                })
                .min_by(|a, b| a.2.total_cmp(&b.2));
            match candidate {
                Some((cause, k, s)) if s < best - c.margin => {
                    free.push(k);
                    model = model.with(cause);
                    best = s;
                }
                Some((_, _, s)) => break Some(s),
                None => break None,
            }
        };
        Selection {
            model,
            base,
            free,
            relative: best,
            absolute: base_score + best,
            next,
        }
    }
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

/// The outcome of one forward selection ([`SelfCalibration::select`]).
struct Selection {
    model: CorrectionModel,
    /// The rotation terms' correction that the horizontal terms are fitted on.
    base: VectorK,
    /// Indices of the horizontal terms chosen.
    free: Vec<usize>,
    /// Held-out score relative to the base, χ² units.
    relative: f64,
    /// Held-out score relative to no correction at all, χ² units.
    absolute: f64,
    /// Held-out score of the best term not chosen.
    next: Option<f64>,
}

fn finite(info: &MatrixK, grad: &VectorK) -> bool {
    info.iter().chain(grad.iter()).all(|v| v.is_finite())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn fits_on_a_base_and_names() {
        let mut q = QuadraticCost::default();
        for k in 0..K {
            q.a[(k, k)] = 2.0 + k as f64;
            q.b[k] = 1.0;
        }
        q.a[(0, 1)] = 1.0;
        q.a[(1, 0)] = 1.0;
        let base = VectorK::from([0.0, 0.5, 0.0, 0.0, 0.0, 0.0]);
        // Only the offset free: a00 z = b0 - (A base)_0.
        let c = fit_on_base(&q, &base, &[0]);
        assert!((c[0] - (1.0 - 0.5) / 2.0).abs() < 1e-9 && c[1] == 0.5);
        assert_eq!(fit_on_base(&q, &base, &[]), base);
        // No information: the base.
        assert_eq!(fit_on_base(&QuadraticCost::default(), &base, &[0]), base);
        let m = CorrectionModel::PRINCIPAL_POINT.with(CorrectionModel::YAW);
        assert_eq!(m.name(), "principal-point+yaw");
        assert_eq!(CorrectionModel::parse(&m.name()), Ok(m));
        assert_eq!(CorrectionModel::parse("none"), Ok(CorrectionModel::NONE));
        assert!(CorrectionModel::parse("tilt").is_err());
    }

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
