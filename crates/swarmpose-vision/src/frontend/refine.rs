//! Weighted refinement of a motion on stereo correspondences: stereo depth noise grows
//! with the square of the depth, so an unweighted least-squares fit lets the far points
//! dominate the translation. Each round keeps the points within `k σ_i` and refits
//! with weights `1 / σ_i²` ([`swarmpose_core::arun_weighted`]).

use nalgebra::Isometry3;
use swarmpose_core::{Correspondences, MIN_CORRESPONDENCES, PoseError, arun_weighted};

/// Refines `start` on `data` (which must carry per-point noise levels; without them all
/// weights are 1 and the tolerance is `k` metres): up to `rounds` rounds of inlier
/// selection `|dst_i - (R src_i + t)| < k σ_i` and weighted refit. Returns the motion and
/// its inliers (ascending).
///
/// # Errors
/// [`PoseError::InsufficientSupport`]-style errors from the refit when fewer than
/// [`MIN_CORRESPONDENCES`] points are inliers of `start`.
pub fn refine_weighted(
    data: &Correspondences,
    start: &Isometry3<f64>,
    k: f64,
    rounds: usize,
) -> Result<(Isometry3<f64>, Vec<usize>), PoseError> {
    let sigma = |i: usize| data.noise_sigma().map_or(1.0, |s| s[i]);
    let inliers_of = |pose: &Isometry3<f64>| -> Vec<usize> {
        (0..data.len())
            .filter(|&i| (data.dst()[i] - pose * data.src()[i]).norm() < k * sigma(i))
            .collect()
    };
    let mut pose = *start;
    let mut inliers = inliers_of(&pose);
    for _ in 0..rounds {
        if inliers.len() < MIN_CORRESPONDENCES {
            return Err(PoseError::TooFewPoints {
                needed: MIN_CORRESPONDENCES,
                got: inliers.len(),
            });
        }
        let src: Vec<_> = inliers.iter().map(|&i| data.src()[i]).collect();
        let dst: Vec<_> = inliers.iter().map(|&i| data.dst()[i]).collect();
        let w: Vec<f64> = inliers
            .iter()
            .map(|&i| 1.0 / (sigma(i) * sigma(i)))
            .collect();
        pose = arun_weighted(&src, &dst, Some(&w))?;
        let next = inliers_of(&pose);
        if next == inliers {
            break;
        }
        inliers = next;
    }
    Ok((pose, inliers))
}

pub use swarmpose_core::CHI2_3_99;

/// Refines `start` by minimising the Mahalanobis residuals of stereo points: residual
/// `r_i = dst_i - (R src_i + t)` with covariance `R Σ_src,i Rᵀ + Σ_dst,i` (elongated
/// along the viewing rays, so depth noise does not swamp the precise lateral
/// positions). The core's [`swarmpose_core::refine_mahalanobis`] on `data` with these
/// covariances attached. Returns the motion and its inliers.
///
/// # Errors
/// [`PoseError::LengthMismatch`] or [`PoseError::InvalidConfig`] for covariances of the
/// wrong length or not positive definite; [`PoseError::InsufficientSupport`] when fewer
/// than [`MIN_CORRESPONDENCES`] points pass the gate.
pub fn refine_stereo(
    data: &Correspondences,
    src_cov: &[nalgebra::Matrix3<f64>],
    dst_cov: &[nalgebra::Matrix3<f64>],
    start: &Isometry3<f64>,
    gate: f64,
    rounds: usize,
) -> Result<(Isometry3<f64>, Vec<usize>), PoseError> {
    let with_cov = Correspondences::new(data.src().to_vec(), data.dst().to_vec())?
        .with_noise_covariance(src_cov.to_vec(), dst_cov.to_vec())?;
    swarmpose_core::refine_mahalanobis(&with_cov, start, gate, rounds)
}
