//! Estimators of the rigid motion `dst = R src + t` behind one trait, so the paper's
//! method, the baselines and new ideas are compared by the same code.

mod consensus;
mod mahalanobis;
mod mixture;
mod msac;
mod pso_paper;
mod pso_robust;
mod ray_noise;
pub mod registry;
mod svd;
#[cfg(test)]
mod test_scenes;
mod wls;

use std::time::Duration;

use nalgebra::Isometry3;

use crate::error::PoseError;
use crate::geometry::Correspondences;
use crate::rng::{SeededRng, seeded};

pub use consensus::{
    Tolerance, collect_inliers, collect_inliers_within, residual_rms, truncated_cost,
    truncated_cost_within,
};
pub use mahalanobis::{CHI2_3_99, refine_mahalanobis};
pub use msac::{MAX_SAMPLES, MsacConfig, MsacEstimator};
pub use pso_paper::{PsoPaperConfig, PsoPaperEstimator};
pub use pso_robust::{PsoEstimator, PsoEstimatorConfig, Threshold};
pub use ray_noise::RangeNoise;
pub use registry::{EstimatorConfig, Method};
pub use svd::SvdEstimator;
pub use wls::WlsEstimator;

/// Counters and timings of one estimation.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Diagnostics {
    /// Iterations of the method's main loop (PSO iterations, MSAC samples; 1 for SVD).
    pub iterations: usize,
    /// Evaluations of a cost or fitness function over the data.
    pub cost_evaluations: u64,
    /// Final cost: the truncated quadratic (MSAC) cost `Σ min(r², δ²)` in m² of the
    /// returned pose over all correspondences, or `Σ r²` for methods without a threshold.
    pub final_cost: f64,
    /// Root mean square of the residuals `|dst - (R src + t)|` over the inliers, metres.
    pub residual_rms_m: f64,
    /// Inlier threshold δ used, metres (`None` for methods without one).
    pub threshold_m: Option<f64>,
    /// Wall-clock time of the estimation call.
    pub elapsed: Duration,
    /// A second motion with comparable support, when the estimator looked for one and
    /// found it: the answer is ambiguous (for example a moving object covering much of
    /// the view).
    pub runner_up: Option<RunnerUp>,
    /// The range-dependent noise model that plain coordinates' residuals chose over
    /// isotropic noise, when they did (`pso` only): the fit and the inlier test then used
    /// its covariances ([`RangeNoise`]).
    pub range_noise: Option<RangeNoise>,
}

/// A second rigid motion found among the correspondences the estimate left over.
#[derive(Debug, Clone, PartialEq)]
pub struct RunnerUp {
    /// Its motion, `dst ≈ R src + t`.
    pub transform: Isometry3<f64>,
    /// 0-based indices of its inliers, ascending.
    pub inliers: Vec<usize>,
}

/// What an estimator returns.
#[derive(Debug, Clone, PartialEq)]
pub struct Estimate {
    /// The motion, mapping source to destination: `dst ≈ R src + t`, metres.
    pub transform: Isometry3<f64>,
    /// 0-based indices of the correspondences the pose was fitted to, ascending.
    pub inliers: Vec<usize>,
    /// Counters and timings.
    pub diagnostics: Diagnostics,
}

impl Estimate {
    /// True when a runner-up motion with comparable support was found.
    #[must_use]
    pub fn is_ambiguous(&self) -> bool {
        self.diagnostics.runner_up.is_some()
    }

    /// Fraction of the correspondences that are inliers, in `[0, 1]`.
    #[must_use]
    pub fn inlier_ratio(&self, total: usize) -> f64 {
        if total == 0 {
            0.0
        } else {
            self.inliers.len() as f64 / total as f64
        }
    }
}

/// A method that estimates the rigid motion of a set of correspondences.
///
/// Implementations are deterministic for a given random generator state, never return an
/// improper rotation, and return an error rather than a pose they cannot support.
pub trait Estimator: Send + Sync {
    /// Short name as used on the command line (`pso`, `pso-paper`, `svd`, `msac`).
    fn name(&self) -> &'static str;

    /// Estimates `dst ≈ R src + t`, drawing any randomness from `rng`.
    ///
    /// # Errors
    /// Too few or degenerate points, or too little support for a pose.
    fn estimate(&self, data: &Correspondences, rng: &mut SeededRng) -> Result<Estimate, PoseError>;

    /// [`Estimator::estimate`] with a fresh generator seeded by `seed`.
    ///
    /// # Errors
    /// As [`Estimator::estimate`].
    fn estimate_seeded(&self, data: &Correspondences, seed: u64) -> Result<Estimate, PoseError> {
        self.estimate(data, &mut seeded(seed))
    }
}

#[cfg(test)]
mod tests;
