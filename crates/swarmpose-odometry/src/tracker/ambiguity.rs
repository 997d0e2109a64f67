//! A second motion near the prediction: the check that keeps a large moving object from
//! becoming the camera's motion.
//!
//! The robust estimator takes the motion with the most support. When a vehicle ahead
//! keeps the camera's speed and fills much of the view, that motion is "standing still",
//! and the static world, whose far points the winner's tolerance partly swallows, may
//! hold less than the estimator's ambiguity ratio of it. The constant-velocity
//! prediction tells the two apart: after the refinement, the matches that are not its
//! inliers but agree with the prediction (whitened χ² at most the refinement's first
//! gate) are counted; when they reach [`SECOND_MOTION_RATIO`] of the refined inliers,
//! they are refined on their own, from the prediction. A result that shares less than half
//! of its inliers with the first is a second motion: the frame is ambiguous, and the
//! motion whose inliers the prediction explains better (lower median χ²) is taken.
//!
//! Without a prediction (the first pair, the pair after a lost frame), or when the
//! previous frame was ambiguous already (its motion, and so the prediction, may be the
//! object's), the matches left over by the first motion are searched for a second one by
//! the estimator itself ([`leftover_motion`]); a second motion with a quarter of the
//! first's inliers flags the frame, with nothing to choose between them by.
//!
//! Everything is measured in whitened pixels, so the check does not depend on the unit of
//! the calibration or on the scene's size. A wrong prediction (a sudden change of speed)
//! finds no support and changes nothing.

use nalgebra::{Isometry3, UnitQuaternion};

use swarmpose_core::{Correspondences, Estimator};

use crate::refine::model::{StereoModel, StereoObservation};
use crate::refine::{Prepared, RefineConfig, Refined, refine};

/// Share of the first motion's inliers that the matches agreeing with the prediction
/// must reach before they are refined as a second motion: a quarter (the robust
/// estimator reports a runner-up from a half on).
pub(crate) const SECOND_MOTION_RATIO: f64 = 0.25;

/// Whitened χ² of each match under `motion` (the pose of B in A), its point placed
/// where A measured it; `f64::INFINITY` when the point is not in front of either camera.
fn chi2_under(
    model: &StereoModel,
    motion: &Isometry3<f64>,
    reference: &[StereoObservation],
    current: &[StereoObservation],
) -> Vec<f64> {
    // The model's constants once, and its correction inlined (issue 34).
    let model = Prepared::new(model);
    let a_in_b = motion.inverse();
    let rot = *a_in_b.rotation.to_rotation_matrix().matrix();
    let trans = a_in_b.translation.vector;
    reference
        .iter()
        .zip(current)
        .map(|(a, b)| {
            let p = model.anchor(a);
            if p.z <= 0.0 || !p.iter().all(|v| v.is_finite()) {
                return f64::INFINITY;
            }
            model
                .residual2_in_current(&rot, &trans, &p, b)
                .unwrap_or(f64::INFINITY)
        })
        .collect()
}

/// Median of `chi2` at `indices` (infinite for none).
fn median_at(chi2: &[f64], indices: &[usize]) -> f64 {
    let mut v: Vec<f64> = indices.iter().map(|&i| chi2[i]).collect();
    if v.is_empty() {
        return f64::INFINITY;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// A second motion found near the prediction.
pub(crate) struct Second {
    /// The motion, refined; its inliers index the full match lists.
    pub refined: Refined,
    /// The prediction explains its inliers better than the first motion's (lower median
    /// whitened χ² under the prediction): it is the one to take.
    pub preferred: bool,
}

/// A second motion of the matches `(reference, current)` near `prediction` (the pose of
/// B in A at constant velocity), distinct from `first` (refined from the estimator's
/// motion), given each match's fold; `None` when there is none.
pub(crate) fn second_motion(
    model: &StereoModel,
    config: &RefineConfig,
    (reference, current, folds): (&[StereoObservation], &[StereoObservation], &[u8]),
    first: &Refined,
    prediction: &Isometry3<f64>,
    min_inliers: usize,
) -> Option<Second> {
    let chi2 = chi2_under(model, prediction, reference, current);
    let in_first = inlier_mask(first, reference.len());
    let outside = (0..reference.len())
        .filter(|&i| !in_first[i] && chi2[i] <= config.initial_gate_chi2)
        .count();
    let needed = needed(first, min_inliers);
    if outside < needed {
        return None;
    }
    // Refined from the prediction on the matches it explains, so that the first motion's
    // matches do not pull it back.
    let near: Vec<usize> = (0..reference.len())
        .filter(|&i| chi2[i] <= config.initial_gate_chi2)
        .collect();
    let second = refine_subset(
        model,
        config,
        (reference, current, folds),
        &near,
        prediction,
        min_inliers,
    )?;
    let refined = distinct(second, &in_first, needed)?;
    let preferred = median_at(&chi2, &refined.inliers) < median_at(&chi2, &first.inliers);
    Some(Second { refined, preferred })
}

/// A second motion among the matches that are not `first`'s inliers, found by
/// `estimator` on their 3D points (`correspondences`, indexed by `source`, the match of
/// each measurement) and refined on their measurements: for a frame without a prediction
/// to tell the motions apart (the first pair, the pair after a lost frame) or whose
/// previous frame was ambiguous already. Only its existence is used: there is nothing to
/// choose between the two by.
#[allow(clippy::too_many_arguments)]
pub(crate) fn leftover_motion(
    estimator: &dyn Estimator,
    correspondences: &Correspondences,
    model: &StereoModel,
    config: &RefineConfig,
    (reference, current, folds, source): (
        &[StereoObservation],
        &[StereoObservation],
        &[u8],
        &[usize],
    ),
    first: &Refined,
    min_inliers: usize,
    seed: u64,
) -> Option<Refined> {
    let in_first = inlier_mask(first, reference.len());
    let needed = needed(first, min_inliers);
    let rest: Vec<usize> = (0..reference.len()).filter(|&i| !in_first[i]).collect();
    if rest.len() < needed {
        return None;
    }
    let matches: Vec<usize> = rest
        .iter()
        .filter_map(|&i| source.get(i).copied())
        .collect();
    let found = estimator
        .estimate_seeded(&correspondences.select(&matches), seed)
        .ok()?;
    if found.inliers.len() < needed {
        return None;
    }
    let second = refine_subset(
        model,
        config,
        (reference, current, folds),
        &rest,
        &found.transform,
        min_inliers,
    )?;
    distinct(second, &in_first, needed)
}

/// Which of `n` matches are `first`'s inliers.
fn inlier_mask(first: &Refined, n: usize) -> Vec<bool> {
    let mut mask = vec![false; n];
    for &i in &first.inliers {
        if let Some(f) = mask.get_mut(i) {
            *f = true;
        }
    }
    mask
}

/// Inliers a second motion needs: [`SECOND_MOTION_RATIO`] of `first`'s, and `min_inliers`.
fn needed(first: &Refined, min_inliers: usize) -> usize {
    (SECOND_MOTION_RATIO * first.inliers.len() as f64)
        .ceil()
        .max(min_inliers as f64) as usize
}

/// The refinement from `start` on the matches `subset` (ascending), its inliers indexing
/// the full lists.
fn refine_subset(
    model: &StereoModel,
    config: &RefineConfig,
    (reference, current, folds): (&[StereoObservation], &[StereoObservation], &[u8]),
    subset: &[usize],
    start: &Isometry3<f64>,
    min_inliers: usize,
) -> Option<Refined> {
    let pick = |v: &[StereoObservation]| -> Vec<StereoObservation> {
        subset.iter().map(|&i| v[i]).collect()
    };
    let sub_folds: Vec<u8> = subset.iter().map(|&i| folds[i]).collect();
    let mut refined = refine(
        model,
        config,
        &pick(reference),
        &pick(current),
        Some(&sub_folds),
        start,
        min_inliers,
    )
    .ok()?;
    for k in &mut refined.inliers {
        *k = subset[*k];
    }
    refined.motion.rotation = UnitQuaternion::new_normalize(refined.motion.rotation.into_inner());
    Some(refined)
}

/// `second` if it shares less than half of its inliers with the first motion's
/// (`in_first`) and has `needed` of them.
fn distinct(second: Refined, in_first: &[bool], needed: usize) -> Option<Refined> {
    let shared = second.inliers.iter().filter(|&&i| in_first[i]).count();
    (2 * shared < second.inliers.len() && second.inliers.len() >= needed).then_some(second)
}
