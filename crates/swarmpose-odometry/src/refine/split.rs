//! The split-feature check of a motion's covariance, which needs no ground truth.
//!
//! The pair's inlier matches are cut into two spatially disjoint halves (the left and the
//! right half of the current image, at the median column of the matches), and the motion
//! is refined again on each half alone, from the motion of all. If the covariance is
//! honest, the two estimates differ by their errors only, independent when the halves'
//! measurements are, so the difference `d = ξ₁ − ξ₂` (both in the convention of
//! [`crate::refine`]) has the covariance `C₁ + C₂` and its normalised squared norm
//! `dᵀ (C₁ + C₂)⁻¹ d` has mean 6. Errors shared by all features (the calibration's, a
//! motion of the whole image) move both halves alike and mostly cancel in `d`: only the
//! part of them that the two geometries turn into different motions remains, and that
//! part is added to `C₁ + C₂` (`(G₁ − G₂) Σ_c (G₁ − G₂)ᵀ` for the calibration terms of
//! covariance `Σ_c`, `Gᵢ = ∂ξᵢ/∂c`). Errors shared by the features of one region but not
//! the other (the same texture matched the same wrong way, a local bias) do not cancel,
//! and show as a mean above 6 when the covariance leaves them out.

use nalgebra::{Isometry3, Matrix6, Vector6};

use super::evidence::{Matrix6xK, MatrixK};
use super::model::{StereoModel, StereoObservation};
use super::{RefineConfig, RefineError, Refined, refine};

/// The result of the split-feature check for one pair.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SplitCheck {
    /// `ξ₁ − ξ₂`: the error of the second half's motion from the first's, metres and
    /// radians in the current camera (`T₂ = T₁ ∘ E(d)`).
    pub difference: Vector6<f64>,
    /// Its covariance: under the model, `C₁ + C₂` plus the calibration's part that does
    /// not cancel; in a frame's result, with the systematic floor learned from the frames
    /// before it added ([`super::floor`]).
    pub covariance: Matrix6<f64>,
    /// `dᵀ C⁻¹ d` for that covariance `C` (6 on average when it is honest).
    pub nees: f64,
    /// `dᵀ C⁻¹ d` for the model's covariance, without the systematic floor.
    pub model_nees: f64,
    /// Inliers of each half's refinement.
    pub inliers: [usize; 2],
}

/// `ξ` with `b = a ∘ E(ξ)`, `E(ξ): P ↦ Exp(ω) P + ν` (the convention of the refinement's
/// covariance).
#[must_use]
pub fn motion_difference(a: &Isometry3<f64>, b: &Isometry3<f64>) -> Vector6<f64> {
    let ri = a.rotation.inverse();
    let nu = ri * (b.translation.vector - a.translation.vector);
    let w = (ri * b.rotation).scaled_axis();
    Vector6::new(nu.x, nu.y, nu.z, w.x, w.y, w.z)
}

/// `∂ξ/∂c` of a refinement: `−S⁻¹ S_ξc` over both folds, or `None` when singular.
fn calibration_gain(r: &Refined) -> Option<Matrix6xK> {
    let mut both = r.reduced[0];
    both += &r.reduced[1];
    Some(-(both.pose_pose.try_inverse()? * both.pose_correction))
}

/// The split-feature check of the pair `reference[i]`, `current[i]` over its `inliers`
/// (indices, as [`Refined::inliers`]) at the motion `motion` (`T_AB`), with `model` whose
/// calibration terms have the covariance `calibration` (pixels²): each half refined with
/// `config` from `motion`, at least `min_inliers` inliers each.
///
/// # Errors
/// [`RefineError::TooFewInliers`] when a half has too few consistent matches (fewer than
/// twice `min_inliers` inliers in all), [`RefineError::Singular`] when a half does not
/// determine the motion or the difference's covariance is singular,
/// [`RefineError::LengthMismatch`] for slices of different lengths or an inlier index out
/// of range.
pub fn split_check(
    (model, calibration): (&StereoModel, &MatrixK),
    config: &RefineConfig,
    (reference, current): (&[StereoObservation], &[StereoObservation]),
    inliers: &[usize],
    motion: &Isometry3<f64>,
    min_inliers: usize,
) -> Result<SplitCheck, RefineError> {
    if reference.len() != current.len() || inliers.iter().any(|&i| i >= current.len()) {
        return Err(RefineError::LengthMismatch {
            reference: reference.len(),
            current: current.len(),
        });
    }
    let needed = min_inliers.max(3);
    if inliers.len() < 2 * needed {
        return Err(RefineError::TooFewInliers {
            got: inliers.len() / 2,
            needed,
        });
    }
    // The median column of the inliers in the current image cuts them in two.
    let mut order: Vec<usize> = inliers.to_vec();
    order.sort_by(|&i, &j| current[i].u.total_cmp(&current[j].u));
    let (left, right) = order.split_at(order.len() / 2);
    // One pair of buffers for both halves (the right one is the larger), refilled.
    let (mut a, mut b) = (
        Vec::with_capacity(right.len()),
        Vec::with_capacity(right.len()),
    );
    let mut half = |ids: &[usize]| -> Result<Refined, RefineError> {
        a.clear();
        b.clear();
        a.extend(ids.iter().map(|&i| reference[i]));
        b.extend(ids.iter().map(|&i| current[i]));
        refine(model, config, &a, &b, None, motion, needed)
    };
    let (one, two) = (half(left)?, half(right)?);
    let difference = motion_difference(&one.motion, &two.motion);
    let gain = calibration_gain(&one)
        .zip(calibration_gain(&two))
        .map_or_else(Matrix6xK::zeros, |(g1, g2)| g1 - g2);
    let shared = gain * calibration * gain.transpose();
    let covariance = one.covariance + two.covariance + (shared + shared.transpose()) * 0.5;
    let info = covariance.try_inverse().ok_or(RefineError::Singular)?;
    let nees = (difference.transpose() * info * difference)[0];
    if !nees.is_finite() {
        return Err(RefineError::Singular);
    }
    Ok(SplitCheck {
        difference,
        covariance,
        nees,
        model_nees: nees,
        inliers: [one.inliers.len(), two.inliers.len()],
    })
}
