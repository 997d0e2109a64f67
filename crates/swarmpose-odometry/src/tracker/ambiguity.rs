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
//! Everything is measured in whitened pixels, so the check does not depend on the unit of
//! the calibration or on the scene's size. A wrong prediction (a sudden change of speed)
//! finds no support and changes nothing.

use nalgebra::{Isometry3, UnitQuaternion};

use crate::refine::model::{StereoModel, StereoObservation};
use crate::refine::{RefineConfig, Refined, refine};

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

/// A second motion of the matches `(reference, current)` near `prediction` (the pose of
/// B in A at constant velocity), distinct from `first` (refined from the estimator's
/// motion), given each match's fold; `None` when there is none. The second motion's
/// inliers index the full match lists, like `first`'s.
pub(crate) fn second_motion(
    model: &StereoModel,
    config: &RefineConfig,
    (reference, current, folds): (&[StereoObservation], &[StereoObservation], &[u8]),
    first: &Refined,
    prediction: &Isometry3<f64>,
    min_inliers: usize,
) -> Option<Refined> {
    let chi2 = chi2_under(model, prediction, reference, current);
    let mut in_first = vec![false; reference.len()];
    for &i in &first.inliers {
        if let Some(f) = in_first.get_mut(i) {
            *f = true;
        }
    }
    let outside = (0..reference.len())
        .filter(|&i| !in_first[i] && chi2[i] <= config.initial_gate_chi2)
        .count();
    let needed = (SECOND_MOTION_RATIO * first.inliers.len() as f64)
        .ceil()
        .max(min_inliers as f64) as usize;
    if outside < needed {
        return None;
    }
    // Refined from the prediction on the matches it explains, so that the first motion's
    // matches do not pull it back.
    let near: Vec<usize> = (0..reference.len())
        .filter(|&i| chi2[i] <= config.initial_gate_chi2)
        .collect();
    let pick = |v: &[StereoObservation]| -> Vec<StereoObservation> {
        near.iter().map(|&i| v[i]).collect()
    };
    let sub_folds: Vec<u8> = near.iter().map(|&i| folds[i]).collect();
    let mut second = refine(
        model,
        config,
        &pick(reference),
        &pick(current),
        Some(&sub_folds),
        prediction,
        min_inliers,
    )
    .ok()?;
    for k in &mut second.inliers {
        *k = near[*k];
    }
    let shared = second.inliers.iter().filter(|&&i| in_first[i]).count();
    if 2 * shared >= second.inliers.len() || second.inliers.len() < needed {
        return None;
    }
    second.motion.rotation = UnitQuaternion::new_normalize(second.motion.rotation.into_inner());
    Some(second)
}

/// True when the prediction explains `second`'s inliers better than `first`'s (lower
/// median whitened χ² under `prediction`).
pub(crate) fn prediction_prefers(
    model: &StereoModel,
    (reference, current): (&[StereoObservation], &[StereoObservation]),
    first: &Refined,
    second: &Refined,
    prediction: &Isometry3<f64>,
) -> bool {
    let chi2 = chi2_under(model, prediction, reference, current);
    median_at(&chi2, &second.inliers) < median_at(&chi2, &first.inliers)
}
