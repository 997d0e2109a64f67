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

/// [`refine_stereo`] that also estimates a disparity offset `δ` (pixels) common to both
/// frames: every point `p` of disparity `d` is taken as `p d / (d + δ)`. A wrong
/// horizontal principal point of the right camera shifts all disparities alike and
/// makes the translation too long or too short, more so for far points; with depths
/// spread over a range, the motion reveals it. Returns the motion, `δ` and the inliers.
///
/// # Errors
/// As [`refine_stereo`].
pub fn refine_stereo_offset(
    m: &super::FrameMatches,
    start: &Isometry3<f64>,
    gate: f64,
    rounds: usize,
) -> Result<(Isometry3<f64>, f64, Vec<usize>), PoseError> {
    use nalgebra::{Matrix3, SMatrix, SVector, Translation3, UnitQuaternion, Vector3};
    // Start from the plain refinement and its inliers.
    let (mut pose, inliers) = refine_stereo(
        &m.correspondences,
        &m.src_covariances,
        &m.dst_covariances,
        start,
        gate,
        rounds,
    )?;
    let data = &m.correspondences;
    let mut delta = 0.0f64;
    for _ in 0..10 {
        let mut h = SMatrix::<f64, 7, 7>::zeros();
        let mut g = SVector::<f64, 7>::zeros();
        let rot = pose.rotation.to_rotation_matrix();
        for &i in &inliers {
            let (dj, di) = (m.src_disparities_px[i], m.dst_disparities_px[i]);
            let s = data.src()[i].coords * (dj / (dj + delta));
            let d = data.dst()[i].coords * (di / (di + delta));
            let cov = rot.matrix() * m.src_covariances[i] * rot.matrix().transpose()
                + m.dst_covariances[i];
            let Some(w) = cov.try_inverse() else { continue };
            let q = pose.rotation * s + pose.translation.vector;
            let r = d - q;
            // ∂p/∂δ = -p / (d + δ) for each point.
            let dr_ddelta = -d / (di + delta) + pose.rotation * (s / (dj + delta));
            let mut j = SMatrix::<f64, 3, 7>::zeros();
            j.fixed_view_mut::<3, 3>(0, 0).copy_from(&q.cross_matrix());
            j.fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&(-Matrix3::identity()));
            j.fixed_view_mut::<3, 1>(0, 6).copy_from(&dr_ddelta);
            h += j.transpose() * w * j;
            g += j.transpose() * w * r;
        }
        let Some(step) = h.lu().solve(&(-g)) else {
            break;
        };
        let omega = Vector3::new(step[0], step[1], step[2]);
        let dt = Vector3::new(step[3], step[4], step[5]);
        let dr = UnitQuaternion::from_scaled_axis(omega);
        pose = Isometry3::from_parts(
            Translation3::from(dr * pose.translation.vector + dt),
            dr * pose.rotation,
        );
        delta += step[6];
        if step.norm() < 1e-9 {
            break;
        }
    }
    Ok((pose, delta, inliers))
}

/// Self-calibration of the disparity offset from image data alone: for each set of
/// matches, a robust motion from `estimator` (seeded with `seed + index`), then
/// [`refine_stereo_offset`]; the median of the offsets, pixels. `None` when no set
/// could be registered.
#[must_use]
pub fn estimate_disparity_offset(
    matches: &[super::FrameMatches],
    estimator: &dyn swarmpose_core::Estimator,
    seed: u64,
) -> Option<f64> {
    let mut offsets: Vec<f64> = matches
        .iter()
        .enumerate()
        .filter_map(|(k, m)| {
            let e = estimator
                .estimate_seeded(&m.correspondences, seed.wrapping_add(k as u64))
                .ok()?;
            refine_stereo_offset(m, &e.transform, CHI2_3_99, 10)
                .ok()
                .map(|r| r.1)
                .filter(|d| d.is_finite())
        })
        .collect();
    if offsets.is_empty() {
        return None;
    }
    offsets.sort_by(f64::total_cmp);
    Some(offsets[offsets.len() / 2])
}
