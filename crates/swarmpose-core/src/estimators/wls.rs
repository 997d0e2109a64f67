//! `wls`: weighted least squares over every correspondence, no outlier rejection.
//!
//! With a noise level per point ([`Correspondences::with_noise_sigma`]) Arun's SVD is
//! weighted by `1 / σ_i²`; with per-point covariances
//! ([`Correspondences::with_noise_covariance`]) that fit starts a Gauss-Newton
//! minimisation of the Mahalanobis residuals `Σ_i r_iᵀ Σ_i(R)⁻¹ r_i` over all points
//! ([`super::mahalanobis`] with no gate); without a noise model it is Arun's SVD. On
//! exactly the true inliers (`bench`'s `oracle-weighted`) it is the maximum-likelihood
//! motion, the ceiling of any method that ends with a fit to its inliers.

use super::consensus::{Tolerance, arun_within};
use super::mahalanobis::refine_mahalanobis;
use super::svd::fit_of_all_points;
use super::{Estimate, Estimator};
use crate::error::PoseError;
use crate::geometry::Correspondences;
use crate::rng::SeededRng;

/// Gauss-Newton rounds of the covariance fit.
const ROUNDS: usize = 4;

/// `wls`: weighted least squares over every correspondence (see the module
/// documentation). One wrong match biases it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct WlsEstimator;

impl Estimator for WlsEstimator {
    fn name(&self) -> &'static str {
        "wls"
    }

    fn estimate(&self, data: &Correspondences, _: &mut SeededRng) -> Result<Estimate, PoseError> {
        fit_of_all_points(data, |inliers| {
            let tol = data
                .noise_sigma()
                .map_or(Tolerance::Uniform(1.0), Tolerance::PerPoint);
            let transform = arun_within(data, inliers, tol)?;
            if data.noise_covariance().is_none() {
                return Ok(transform);
            }
            // No gate: every point counts.
            Ok(refine_mahalanobis(data, &transform, f64::MAX, ROUNDS)?.0)
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::estimators::test_scenes::stereo_scene;
    use crate::geometry::rotation_angle_between;

    #[test]
    fn covariance_fit_on_true_inliers_beats_plain_svd() {
        let (mut better, mut total) = (0, 0);
        for seed in 0..10 {
            let (data, truth, inlier) = stereo_scene(seed, 1_000_000);
            let idx: Vec<usize> = (0..data.len()).filter(|&i| inlier[i]).collect();
            let sel = data.select(&idx);
            let w = WlsEstimator.estimate_seeded(&sel, 0).expect("fit");
            let plain =
                Correspondences::new(sel.src().to_vec(), sel.dst().to_vec()).expect("valid");
            let s = super::super::SvdEstimator
                .estimate_seeded(&plain, 0)
                .expect("fit");
            let err = |p: &nalgebra::Isometry3<f64>| {
                (p.translation.vector - truth.translation.vector).norm()
                    + rotation_angle_between(&p.rotation, &truth.rotation)
            };
            better += usize::from(err(&w.transform) < err(&s.transform));
            total += 1;
        }
        assert!(better >= 9, "{better}/{total}");
    }
}
