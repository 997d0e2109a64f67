//! The non-robust baseline: Arun's SVD on all correspondences.

use std::time::Instant;

use super::consensus::{arun_on, check_input, residual_sq};
use super::{Diagnostics, Estimate, Estimator};
use crate::error::PoseError;
use crate::geometry::Correspondences;
use crate::rng::SeededRng;

/// `svd`: least squares over every correspondence (Arun 1987), no outlier rejection.
/// Exact on noise-free, outlier-free data; one wrong match biases it.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SvdEstimator;

impl Estimator for SvdEstimator {
    fn name(&self) -> &'static str {
        "svd"
    }

    fn estimate(&self, data: &Correspondences, _: &mut SeededRng) -> Result<Estimate, PoseError> {
        fit_of_all_points(data, |inliers| arun_on(data, inliers))
    }
}

/// The estimate of the motion `fit` to every correspondence (no rejection; `fit` is given
/// the indices of all of them), once the input is checked: all points are inliers, the
/// cost is the sum of squared residuals, m², and the time is that of the whole call.
///
/// # Errors
/// Those of the input check and of `fit`.
pub(crate) fn fit_of_all_points(
    data: &Correspondences,
    fit: impl FnOnce(&[usize]) -> Result<nalgebra::Isometry3<f64>, PoseError>,
) -> Result<Estimate, PoseError> {
    let start = Instant::now();
    check_input(data)?;
    let inliers: Vec<usize> = (0..data.len()).collect();
    let transform = fit(&inliers)?;
    let cost: f64 = data
        .src()
        .iter()
        .zip(data.dst())
        .map(|(s, d)| residual_sq(&transform, s, d))
        .sum();
    Ok(Estimate {
        transform,
        diagnostics: Diagnostics {
            iterations: 1,
            cost_evaluations: 1,
            final_cost: cost,
            residual_rms_m: (cost / data.len() as f64).sqrt(),
            threshold_m: None,
            elapsed: start.elapsed(),
            runner_up: None,
            range_noise: None,
        },
        inliers,
    })
}
