//! The rounds of gating and refitting of [`super::refine`], and its call for the runtime
//! dispatch ([`swarmpose_vision::simd::dispatch`]): the whole refinement is compiled for the
//! CPU's best instruction set, the same IEEE operations in the same order (issue 34).

use nalgebra::{Isometry3, Vector3};
use swarmpose_vision::simd::Kernel;

use super::model::{StereoModel, StereoObservation};
use super::{Fitted, Problem, RefineConfig, RefineError, Refined, Work, fit_point, refine_with};
use crate::nls::pose::Pose;
use crate::nls::robust::huber_cost;

/// A call of [`super::refine`] (its slices of equal lengths) for the dispatch.
pub(super) struct Refine<'a> {
    pub(super) model: &'a StereoModel,
    pub(super) config: &'a RefineConfig,
    /// The reference's and the current frame's measurements, and the folds.
    pub(super) matches: (
        &'a [StereoObservation],
        &'a [StereoObservation],
        Option<&'a [u8]>,
    ),
    pub(super) start: &'a Isometry3<f64>,
    pub(super) min_inliers: usize,
}

impl Kernel for Refine<'_> {
    type Output = Result<Refined, RefineError>;

    #[inline(always)]
    fn run(self) -> Self::Output {
        refine_with(
            self.model,
            self.config,
            self.matches,
            self.start,
            self.min_inliers,
        )
    }
}

/// The gate of the first round: the configuration's, or the median χ² of the matches
/// `fitted` at the starting pose when that is larger (the first round keeps the better
/// half, in case the start is rough).
#[inline(always)]
fn first_gate(config: &RefineConfig, fitted: &[Fitted]) -> f64 {
    let mut chi2s: Vec<f64> = Vec::with_capacity(fitted.len());
    chi2s.extend(fitted.iter().filter_map(|f| f.map(|(_, a2, b2)| a2 + b2)));
    let median = if chi2s.is_empty() {
        0.0
    } else {
        let mid = chi2s.len() / 2;
        *chi2s.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    config.initial_gate_chi2.max(median)
}

impl Problem<'_> {
    /// Rounds of gating the matches `fitted` (each one's point and χ², fitted to the
    /// pose) and refining `pose` on those within the gate, until the gated set settles
    /// or [`RefineConfig::rounds`] are done; every match is fitted again to each new
    /// pose that a next round gates on (`fitted` is left as the last gate saw it).
    /// Leaves the last round's matches in `self.active` and their points in `points`;
    /// returns the Levenberg-Marquardt iterations.
    #[inline(always)]
    pub(super) fn gated_rounds(
        &mut self,
        pose: &mut Pose,
        fitted: &mut [Fitted],
        points: &mut Vec<Vector3<f64>>,
        work: &mut Work,
        needed: usize,
    ) -> Result<usize, RefineError> {
        let mut gate = first_gate(self.config, fitted);
        let mut iterations = 0;
        // Each round's buffers: the matches within the gate and their points.
        let mut active: Vec<usize> = Vec::with_capacity(fitted.len());
        self.active.reserve(fitted.len());
        let rounds = self.config.rounds.max(1);
        for round in 0..rounds {
            active.clear();
            active.extend(
                fitted
                    .iter()
                    .enumerate()
                    .filter_map(|(i, f)| f.and_then(|(_, a2, b2)| (a2 + b2 <= gate).then_some(i))),
            );
            if active.len() < needed {
                return Err(RefineError::TooFewInliers {
                    got: active.len(),
                    needed,
                });
            }
            let settled = round > 0 && active == self.active;
            std::mem::swap(&mut self.active, &mut active);
            if settled {
                break;
            }
            // The points and their cost at `pose` ([`Problem::cost`]) from their fit to
            // it: the same residuals, not computed again (issue 34).
            points.clear();
            let k = self.config.huber_k;
            let mut total = 0.0;
            for &i in &self.active {
                if let Some((p, a2, b2)) = fitted[i] {
                    points.push(p);
                    total += huber_cost(a2, k) + huber_cost(b2, k);
                }
            }
            iterations += self.solve(pose, points, 0.5 * total, work)?;
            if round + 1 == rounds {
                // No round gates on them: the last round's refit would be thrown away
                // (issue 34: every match fitted twice more for nothing).
                break;
            }
            self.refit(pose, fitted);
            gate = self.config.gate_chi2;
        }
        Ok(iterations)
    }

    /// Every match of `fitted` fitted again to `pose`, for the next gate.
    #[inline(always)]
    fn refit(&self, pose: &Pose, fitted: &mut [Fitted]) {
        let (model, reference, current) = (self.model, self.reference, self.current);
        for (i, f) in fitted.iter_mut().enumerate() {
            let start = match f {
                Some((p, _, _)) => *p,
                None => model.anchor(&reference[i]),
            };
            *f = if start.z > 0.0 {
                fit_point(model, pose, start, &reference[i], &current[i])
            } else {
                None
            };
        }
    }
}
