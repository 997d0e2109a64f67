//! `pso-paper`: the paper's PSO/SVD, literally (sections 4-5).

use std::f64::consts::PI;
use std::time::Instant;

use nalgebra::{Matrix3, Vector3};

use super::consensus::{
    arun_on, check_input, check_support, check_threshold, thresholded_estimate,
};
use super::{Estimate, Estimator};
use crate::error::PoseError;
use crate::geometry::{Correspondences, rotation_from_particle, wrap_rotation_vector};
use crate::pso::{ParticleSwarm, PsoConfig};
use crate::rng::SeededRng;
use crate::settings::{self, InvalidSetting, Path};

/// Settings of [`PsoPaperEstimator`]. Defaults in brackets.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct PsoPaperConfig {
    /// Support threshold δ of eq. (15), metres [0.1]. The paper compares the squared
    /// residual with δ; here δ is a distance: a feature supports `q` when
    /// `|r'_j - q r_j q^-1| < δ`.
    pub threshold_m: f64,
    /// The swarm [32 particles, 100 iterations, α = 0.9, c = 1.5, no early stop].
    pub pso: PsoConfig,
}

impl Default for PsoPaperConfig {
    fn default() -> Self {
        Self {
            threshold_m: 0.1,
            pso: PsoConfig::default(),
        }
    }
}

impl PsoPaperConfig {
    /// Sets δ (metres).
    #[must_use]
    pub fn with_threshold(mut self, threshold_m: f64) -> Self {
        self.threshold_m = threshold_m;
        self
    }

    /// Checks every setting's range, naming each below `prefix` (`estimator`) as in a
    /// run configuration: δ finite and above 0, the swarm's ranges ([`PsoConfig::check`]).
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of its range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        let at = Path::root(prefix);
        settings::positive(at.child("threshold_m"), self.threshold_m)?;
        self.pso.check_at(&at.child("pso"))
    }

    /// Sets the swarm settings.
    #[must_use]
    pub fn with_pso(mut self, pso: PsoConfig) -> Self {
        self.pso = pso;
        self
    }
}

/// `pso-paper`: the method exactly as published.
///
/// 1. Centre both sets on their centroids over **all** correspondences, eq. (7)-(8):
///    `r_j = p_j - p̄`, `r'_j = p'_j - p̄'`.
/// 2. Swarm over rotation vectors in `[-π, π]^3` (see [`crate::geometry::rotation_from_particle`])
///    minimising eq. (13) summed over all correspondences,
///    `f(q) = Σ_j |r'_j - q r_j q^-1|^2`. Each particle stores the support of its best
///    position, the number of `j` with residual below δ, eq. (15); the best particle
///    has the most support, ties broken by lower fitness. (Letting support drive the
///    swarm instead traps it: a point near the centroid "supports" any rotation.)
/// 3. The best particle's supporting features are refined by SVD (Arun); fewer than 4 is
///    [`PoseError::InsufficientSupport`].
///
/// Faithful, and fragile: outliers move the centroids of step 1, so every residual is
/// biased by `p̄' - R p̄ - t` and with a tenth of the matches wrong no inlier may pass δ
/// (see the tests). Kept as the reference; [`super::PsoEstimator`] is the working variant.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PsoPaperEstimator {
    /// The settings.
    pub config: PsoPaperConfig,
}

impl PsoPaperEstimator {
    /// A `pso-paper` estimator with these settings.
    #[must_use]
    pub fn new(config: PsoPaperConfig) -> Self {
        Self { config }
    }
}

/// Centred copies of the sets on their all-point centroids.
fn centred(data: &Correspondences) -> (Vec<Vector3<f64>>, Vec<Vector3<f64>>) {
    let n = data.len() as f64;
    let cs = data.src().iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
    let cd = data.dst().iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
    (
        data.src().iter().map(|p| p.coords - cs).collect(),
        data.dst().iter().map(|p| p.coords - cd).collect(),
    )
}

impl Estimator for PsoPaperEstimator {
    fn name(&self) -> &'static str {
        "pso-paper"
    }

    fn estimate(&self, data: &Correspondences, rng: &mut SeededRng) -> Result<Estimate, PoseError> {
        let start = Instant::now();
        let cfg = &self.config;
        check_threshold(cfg.threshold_m)?;
        check_input(data)?;
        let (r, r_prime) = centred(data);
        let thr2 = cfg.threshold_m * cfg.threshold_m;
        let n = data.len();
        let rotation_of = |x: &[f64; 3]| -> Matrix3<f64> {
            rotation_from_particle(x).to_rotation_matrix().into_inner()
        };
        // The swarm minimises eq. (13) summed over all correspondences.
        let fitness = |x: &[f64; 3]| -> f64 {
            let m = rotation_of(x);
            r.iter()
                .zip(&r_prime)
                .map(|(a, b)| (b - m * a).norm_squared())
                .sum()
        };
        let support_of = |m: &Matrix3<f64>| -> Vec<usize> {
            (0..n)
                .filter(|&j| (r_prime[j] - m * r[j]).norm_squared() < thr2)
                .collect()
        };
        let swarm = ParticleSwarm::new(cfg.pso.clone());
        let out =
            swarm.minimize_projected([-PI; 3], [PI; 3], &[], rng, wrap_rotation_vector, fitness)?;
        // Each particle keeps its support, eq. (15); the best particle has the most, ties
        // broken by the lower fitness.
        let mut inliers: Vec<usize> = Vec::new();
        let mut best_fitness = f64::INFINITY;
        for (x, f) in &out.personal_bests {
            let support = support_of(&rotation_of(x));
            if support.len() > inliers.len()
                || (support.len() == inliers.len() && *f < best_fitness)
            {
                inliers = support;
                best_fitness = *f;
            }
        }
        check_support(data, &inliers)?;
        let transform = arun_on(data, &inliers)?;
        Ok(thresholded_estimate(
            data,
            transform,
            inliers,
            cfg.threshold_m,
            (out.iterations, out.evaluations),
            start,
        ))
    }
}
