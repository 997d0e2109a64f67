//! The robust baseline: MSAC (Torr & Zisserman 2000).

use std::time::Instant;

use nalgebra::Isometry3;
use rand::seq::index::sample_array;

use super::consensus::{check_input, refine, residual_sq, thresholded_estimate};
use super::{Estimate, Estimator};
use crate::arun::arun_pairs;
use crate::error::PoseError;
use crate::geometry::Correspondences;
use crate::rng::SeededRng;
use crate::settings::{self, InvalidSetting, Path};

/// Settings of [`MsacEstimator`]. Defaults in brackets.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct MsacConfig {
    /// Inlier threshold δ on `|dst - (R src + t)|`, metres [0.1]. About `3.4 σ` for
    /// isotropic Gaussian noise of σ per axis (99 % of inliers).
    pub threshold_m: f64,
    /// Probability that at least one all-inlier sample was drawn when sampling stops
    /// [0.999].
    pub confidence: f64,
    /// Cap on the number of samples \[100000\].
    pub max_iterations: usize,
    /// Least number of samples drawn whatever the adaptive count says \[10\].
    pub min_iterations: usize,
    /// Rounds of (inliers, SVD refit) after sampling \[5\].
    pub refine_rounds: usize,
}

impl Default for MsacConfig {
    fn default() -> Self {
        Self {
            threshold_m: 0.1,
            confidence: 0.999,
            max_iterations: 100_000,
            min_iterations: 10,
            refine_rounds: 5,
        }
    }
}

impl MsacConfig {
    /// Sets the inlier threshold (metres).
    #[must_use]
    pub fn with_threshold(mut self, threshold_m: f64) -> Self {
        self.threshold_m = threshold_m;
        self
    }

    /// Sets the confidence level in `(0, 1)`.
    #[must_use]
    pub fn with_confidence(mut self, confidence: f64) -> Self {
        self.confidence = confidence;
        self
    }

    /// Sets the sample cap.
    #[must_use]
    pub fn with_max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }

    fn validate(&self) -> Result<(), PoseError> {
        Ok(self.check("")?)
    }

    /// Checks every setting's range, naming each below `prefix` (`estimator`) as in a
    /// run configuration: a threshold finite and above 0, a confidence in `(0, 1)`, the
    /// counts from 1 to [`MAX_SAMPLES`].
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of its range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        self.check_at(&Path::root(prefix))
    }

    /// [`Self::check`] below the path `at`.
    pub(crate) fn check_at(&self, at: &Path<'_>) -> Result<(), InvalidSetting> {
        let name = |n| at.child(n);
        settings::positive(name("threshold_m"), self.threshold_m)?;
        settings::open_unit(name("confidence"), self.confidence)?;
        settings::count_within(name("max_iterations"), self.max_iterations, 1, MAX_SAMPLES)?;
        settings::count_within(name("refine_rounds"), self.refine_rounds, 1, MAX_SAMPLES)?;
        Ok(())
    }
}

/// Most samples (and refinement rounds) MSAC may draw: bounded work per estimate
/// (`--max-samples 10^18` with a confidence near 1 ran for ever).
pub const MAX_SAMPLES: usize = 10_000_000;

/// `msac`: 3-point minimal samples solved by SVD, scored by the truncated quadratic cost
/// `Σ min(r², δ²)`, with the adaptive sample count `k = log(1 - p) / log(1 - w³)` for
/// confidence `p` and best inlier ratio so far `w`; then a refit on the inliers.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct MsacEstimator {
    /// The settings.
    pub config: MsacConfig,
}

impl MsacEstimator {
    /// An MSAC estimator with these settings.
    #[must_use]
    pub fn new(config: MsacConfig) -> Self {
        Self { config }
    }
}

/// Samples needed so that an all-inlier 3-sample was drawn with probability `confidence`
/// when a fraction `w` of the data are inliers.
fn adaptive_iterations(confidence: f64, w: f64, cap: usize) -> usize {
    let p_good = w.powi(3);
    if p_good >= 1.0 {
        return 1;
    }
    if p_good <= 0.0 {
        return cap;
    }
    let k = (1.0 - confidence).ln() / (1.0 - p_good).ln();
    if k.is_finite() {
        (k.ceil() as usize).min(cap)
    } else {
        cap
    }
}

impl Estimator for MsacEstimator {
    fn name(&self) -> &'static str {
        "msac"
    }

    fn estimate(&self, data: &Correspondences, rng: &mut SeededRng) -> Result<Estimate, PoseError> {
        let start = Instant::now();
        let cfg = &self.config;
        cfg.validate()?;
        check_input(data)?;
        let (src, dst) = (data.src(), data.dst());
        let n = data.len();
        let thr2 = cfg.threshold_m * cfg.threshold_m;
        let mut best: Option<(f64, Isometry3<f64>)> = None;
        let mut needed = cfg.max_iterations;
        let mut iterations = 0;
        let mut evaluations = 0u64;
        while iterations < needed.max(cfg.min_iterations).min(cfg.max_iterations) {
            iterations += 1;
            let Some(idx) = sample_array::<_, 3>(rng, n) else {
                break;
            };
            let Ok(pose) = arun_pairs(idx.iter().map(|&i| (&src[i], &dst[i], 1.0))) else {
                continue; // collinear sample
            };
            evaluations += 1;
            let bound = best.as_ref().map_or(f64::INFINITY, |b| b.0);
            let mut cost = 0.0;
            let mut count = 0usize;
            for (s, d) in src.iter().zip(dst) {
                let r2 = residual_sq(&pose, s, d);
                if r2 < thr2 {
                    count += 1;
                    cost += r2;
                } else {
                    cost += thr2;
                }
                if cost >= bound {
                    break;
                }
            }
            if cost < bound {
                best = Some((cost, pose));
                needed = adaptive_iterations(
                    cfg.confidence,
                    count as f64 / n as f64,
                    cfg.max_iterations,
                );
            }
        }
        let Some((_, hypothesis)) = best else {
            return Err(PoseError::InsufficientSupport {
                support: 0,
                needed: crate::geometry::MIN_CORRESPONDENCES,
            });
        };
        let mut inliers = Vec::with_capacity(n);
        let transform = refine(
            data,
            &hypothesis,
            cfg.threshold_m,
            cfg.refine_rounds,
            &mut inliers,
        )?;
        Ok(thresholded_estimate(
            data,
            transform,
            inliers,
            cfg.threshold_m,
            (iterations, evaluations),
            start,
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn adaptive_count_matches_formula() {
        // w = 0.5: log(0.001) / log(1 - 0.125) = 51.7 -> 52.
        assert_eq!(adaptive_iterations(0.999, 0.5, 100_000), 52);
        assert_eq!(adaptive_iterations(0.999, 1.0, 100_000), 1);
        assert_eq!(adaptive_iterations(0.999, 0.0, 777), 777);
        assert_eq!(adaptive_iterations(0.999, 0.01, 1000), 1000);
    }
}
