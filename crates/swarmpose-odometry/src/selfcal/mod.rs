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
mod fit;
pub mod rows;
pub mod scene;
mod subset;

pub use causes::CorrectionModel;
pub use fit::applied_fraction;
use fit::{covariance_on, fit_on_base, rows_covariance};

use swarmpose_vision::frontend::{CORRECTION_TERMS, DisparityCorrection};
use swarmpose_vision::stereo::RectifiedStereo;

use crate::refine::evidence::{MatrixK, QuadraticCost, Reduced, VectorK};
use crate::refine::model::FOCAL_TERM;
use rows::{RowDecision, RowEvidence};
use subset::Terms;

pub(crate) const K: usize = crate::refine::model::CALIBRATION_TERMS;

/// Settings of the self-calibration.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
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
    #[cfg_attr(feature = "serde", serde(with = "crate::config_serde"))]
    pub memory_s: f64,
    /// How many disparity standard deviations a pair's matches must spread about their
    /// best plane in `(u, v, d)` for the pair to add rigidity evidence (default
    /// [`scene::MIN_OFF_PLANE_SIGMAS`], 2; 0 turns the check off): on one plane a
    /// disparity offset cannot be told from the scene's scale ([`scene`]).
    pub min_off_plane_sigmas: f64,
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
            min_off_plane_sigmas: scene::MIN_OFF_PLANE_SIGMAS,
        }
    }
}

/// Index of the linear term (cause [`CorrectionModel::FOCAL`]) among the coefficients.
const FOCAL_INDEX: usize = 2;

/// The horizontal causes, seen by rigidity, and their coefficient index.
const RIGID_CAUSES: [(CorrectionModel, usize); 3] = [
    (CorrectionModel::PRINCIPAL_POINT, 0),
    (CorrectionModel::FOCAL, FOCAL_INDEX),
    (CorrectionModel::FOCAL_LENGTH, FOCAL_TERM),
];

/// The horizontal causes with the `x²` term fitted by rigidity alone (cause
/// [`CorrectionModel::QUADRATIC`]: a disparity error growing towards the image's left and
/// right edges that the rows do not explain as a yaw).
const RIGID_CAUSES_WITH_QUADRATIC: [(CorrectionModel, usize); 4] = [
    (CorrectionModel::PRINCIPAL_POINT, 0),
    (CorrectionModel::QUADRATIC, 1),
    (CorrectionModel::FOCAL, FOCAL_INDEX),
    (CorrectionModel::FOCAL_LENGTH, FOCAL_TERM),
];

/// Why a tracked pair adds no rigidity evidence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum NoEvidence {
    /// Its features moved by less than a pixel: the front end's own sub-pixel errors are
    /// as large as the motion.
    TooLittleMotion,
    /// Its matches lie on one plane ([`scene`]): a disparity offset or a term linear in
    /// `x` is then indistinguishable from the scene's scale.
    OnePlane,
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
    /// Pairs that moved enough but added no rigidity evidence because their matches lay
    /// on one plane ([`scene`]): there a disparity offset cannot be told from the
    /// scene's scale.
    pub one_plane_pairs: usize,
    /// Frames whose confirmed matches gave row evidence.
    pub frames: usize,
}

impl Decision {
    /// True when the rigidity evidence could not observe the calibration: every pair
    /// that moved enough saw one plane ([`Decision::one_plane_pairs`]), so no
    /// horizontal term (offset, linear term) is estimated and none is applied.
    #[must_use]
    pub fn rigidity_unobservable(&self) -> bool {
        self.pairs == 0 && self.one_plane_pairs > 0
    }
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

    /// A pair that adds no rigidity evidence (for the reason `why`), `dt_s` seconds after
    /// its reference: the evidence so far fades over that time, and the decision is
    /// taken again (the rows may have changed).
    pub fn add_pair_without_evidence(&mut self, dt_s: f64, why: NoEvidence) -> &Decision {
        if why == NoEvidence::OnePlane {
            self.decision.one_plane_pairs += 1;
        }
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
        let quadratic_alone = !rows.yaw && c.candidates.has(CorrectionModel::QUADRATIC);
        let mut chosen = self.select(
            &rows,
            if quadratic_alone {
                &RIGID_CAUSES_WITH_QUADRATIC
            } else {
                &RIGID_CAUSES
            },
        );
        if rows.yaw {
            // The rows' x y term need not be a yaw (a rectification left with some
            // distortion bends the rows too): their yaw is kept only if rigidity does
            // not prefer its own x² term by the margin; that term is then named after
            // what rigidity sees, `quadratic`, not a yaw.
            let mut no_yaw = rows;
            no_yaw.yaw = false;
            let own = self.select(&no_yaw, &RIGID_CAUSES_WITH_QUADRATIC);
            if own.model.has(CorrectionModel::QUADRATIC)
                && own.absolute < chosen.absolute - c.margin
            {
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
            one_plane_pairs: self.decision.one_plane_pairs,
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
        // On the stack: a copy for every candidate scored (issue 34).
        let mut free = Terms::<K>::new();
        let mut best = 0.0;
        let next = loop {
            let candidate = causes
                .iter()
                .filter(|(cause, k)| {
                    // Rigidity's own x² term is the alternative to the rows' yaw.
                    let allowed = c.candidates.has(*cause)
                        || (*cause == CorrectionModel::QUADRATIC
                            && c.candidates.has(CorrectionModel::YAW));
                    allowed && !free.contains(k) && determined(*k)
                })
                .map(|&(cause, k)| (cause, k, score(&free.with(k))))
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

/// The outcome of one forward selection ([`SelfCalibration::select`]).
struct Selection {
    model: CorrectionModel,
    /// The rotation terms' correction that the horizontal terms are fitted on.
    base: VectorK,
    /// Indices of the horizontal terms chosen.
    free: Terms<K>,
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
        let q = CorrectionModel::PRINCIPAL_POINT.with(CorrectionModel::QUADRATIC);
        assert_eq!(q.name(), "principal-point+quadratic");
        assert_eq!(CorrectionModel::parse(&q.name()), Ok(q));
    }
}
