//! `pso`: the paper's idea made to work with outliers.
//!
//! The paper scores a rotation on points centred on all-point centroids, which outliers
//! move. Here the rotation is scored on **translation-free pair differences**, which no
//! outlier can bias:
//!
//! ```text
//! a_k = s_i - s_j,   b_k = d_i - d_j,   e_k(R) = b_k - R a_k.
//! ```
//!
//! For two inliers `|e_k(R_true)| < 2δ` whatever `t` is. The steps:
//!
//! 1. **Pairs.** Keep pairs whose lengths agree, `| |b_k| - |a_k| | < 2δ` (a rigid motion
//!    keeps lengths; a random wrong match rarely does), and whose source length is at least
//!    `min(5δ, extent/10)` (short pairs carry little rotation; `extent` is the largest
//!    principal extent of the source points, so small scenes keep their pairs). All `n(n-1)/2` pairs are tested when that
//!    fits `pair_budget`, otherwise random pairs until the budget is spent or `16 max_pairs`
//!    consistent ones are found. At most `max_pairs` of the
//!    consistent ones are scored.
//! 2. **Swarm.** Particles are rotation vectors mapped to unit quaternions
//!    ([`crate::geometry::rotation_from_particle`]). A particle's support is the number of
//!    scored pairs with `|e_k| < 2δ`; the best has the most support, ties broken by the
//!    lower truncated cost `Σ min(|e_k|², 4δ²)`. Part of the swarm starts at rotations
//!    solved from 3-point minimal samples drawn from mutually consistent pairs.
//! 3. **Translation vote.** With the best rotation `R`, each point proposes
//!    `t_i = d_i - R s_i`; among the points taking part in most supporting pairs, the
//!    proposal with the most others within `2δ` wins.
//! 4. **SVD refinement.** Inliers are the points with `|d_i - (R s_i + t)| < δ`; Arun's SVD
//!    refits them, repeated until the inlier set is stable. Fewer than 4 supporting features
//!    is [`PoseError::InsufficientSupport`].

mod pairs;

use std::f64::consts::PI;
use std::time::Instant;

use nalgebra::{Isometry3, Translation3, Vector3};

use super::consensus::{check_input, check_threshold, refine, residual_rms, truncated_cost};
use super::{Diagnostics, Estimate, Estimator};
use crate::error::PoseError;
use crate::geometry::{Correspondences, MIN_CORRESPONDENCES, rotation_from_particle};
use crate::pso::{ParticleSwarm, PsoConfig};
use crate::rng::SeededRng;
use pairs::PairSet;

/// Settings of [`PsoEstimator`]. Defaults in brackets.
#[derive(Debug, Clone, PartialEq)]
pub struct PsoEstimatorConfig {
    /// Inlier threshold δ on `|dst - (R src + t)|`, metres [0.1]. About `3.4 σ` for
    /// isotropic Gaussian noise of σ per axis.
    pub threshold_m: f64,
    /// The swarm [24 particles, 40 iterations, α = 0.9, c = 1.5, stop after 8 iterations
    /// without improvement].
    pub pso: PsoConfig,
    /// Particles started from 3-point minimal samples; the rest start uniformly [12].
    pub seeded_particles: usize,
    /// Most pairs tested for length consistency [250000]; below that all pairs are.
    pub pair_budget: usize,
    /// Most consistent pairs scored per fitness evaluation [512].
    pub max_pairs: usize,
    /// Rounds of (inliers, SVD refit) at the end [5].
    pub refine_rounds: usize,
}

impl Default for PsoEstimatorConfig {
    fn default() -> Self {
        Self {
            threshold_m: 0.1,
            pso: PsoConfig::default()
                .with_swarm_size(24)
                .with_max_iterations(40)
                .with_stall_iterations(Some(8)),
            seeded_particles: 12,
            pair_budget: 250_000,
            max_pairs: 512,
            refine_rounds: 5,
        }
    }
}

impl PsoEstimatorConfig {
    /// Sets δ (metres).
    #[must_use]
    pub fn with_threshold(mut self, threshold_m: f64) -> Self {
        self.threshold_m = threshold_m;
        self
    }

    /// Sets the swarm settings.
    #[must_use]
    pub fn with_pso(mut self, pso: PsoConfig) -> Self {
        self.pso = pso;
        self
    }

    /// Sets how many particles start from minimal samples.
    #[must_use]
    pub fn with_seeded_particles(mut self, n: usize) -> Self {
        self.seeded_particles = n;
        self
    }

    fn validate(&self) -> Result<(), PoseError> {
        check_threshold(self.threshold_m)?;
        self.pso.validate()?;
        if self.pair_budget == 0 || self.max_pairs == 0 || self.refine_rounds == 0 {
            return Err(PoseError::InvalidConfig(
                "pair_budget, max_pairs and refine_rounds must be at least 1".into(),
            ));
        }
        Ok(())
    }
}

/// `pso`: the robust PSO/SVD estimator (see the module documentation).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PsoEstimator {
    /// The settings.
    pub config: PsoEstimatorConfig,
}

impl PsoEstimator {
    /// A `pso` estimator with these settings.
    #[must_use]
    pub fn new(config: PsoEstimatorConfig) -> Self {
        Self { config }
    }
}

/// Number of anchor points whose translation proposals are voted on.
const ANCHORS: usize = 32;

/// Step 3: the translation with the most agreeing proposals `d_i - R s_i`.
fn vote_translation(
    data: &Correspondences,
    pairs: &PairSet,
    rotation: &nalgebra::UnitQuaternion<f64>,
    tol_m: f64,
) -> Option<Vector3<f64>> {
    let m = rotation.to_rotation_matrix().into_inner();
    let proposals: Vec<Vector3<f64>> = data
        .src()
        .iter()
        .zip(data.dst())
        .map(|(s, d)| d.coords - m * s.coords)
        .collect();
    let anchors = pairs.anchors(&m, ANCHORS);
    let tol2 = tol_m * tol_m;
    let mut best: Option<(usize, usize)> = None;
    for &c in &anchors {
        let count = proposals
            .iter()
            .filter(|p| (*p - proposals[c]).norm_squared() < tol2)
            .count();
        if best.is_none_or(|(b, _)| count > b) {
            best = Some((count, c));
        }
    }
    let (_, c) = best?;
    let (sum, k) = proposals
        .iter()
        .filter(|p| (*p - proposals[c]).norm_squared() < tol2)
        .fold((Vector3::zeros(), 0usize), |(s, k), p| (s + p, k + 1));
    Some(sum / k as f64)
}

impl Estimator for PsoEstimator {
    fn name(&self) -> &'static str {
        "pso"
    }

    fn estimate(&self, data: &Correspondences, rng: &mut SeededRng) -> Result<Estimate, PoseError> {
        let start = Instant::now();
        let cfg = &self.config;
        cfg.validate()?;
        check_input(data)?;
        let pair_tol = 2.0 * cfg.threshold_m;
        let pairs = PairSet::build(data, cfg, rng);
        if pairs.is_empty() {
            return Err(PoseError::InsufficientSupport {
                support: 0,
                needed: MIN_CORRESPONDENCES,
            });
        }
        let seeds = pairs.minimal_sample_seeds(data, cfg.seeded_particles, rng);
        let swarm = ParticleSwarm::new(cfg.pso.clone());
        let out = swarm.minimize([-PI; 3], [PI; 3], &seeds, rng, |x| {
            pairs.score(&rotation_from_particle(x), pair_tol)
        })?;
        let rotation = rotation_from_particle(&out.best_position);
        let t = vote_translation(data, &pairs, &rotation, pair_tol).ok_or(
            PoseError::InsufficientSupport {
                support: 0,
                needed: MIN_CORRESPONDENCES,
            },
        )?;
        let hypothesis = Isometry3::from_parts(Translation3::from(t), rotation);
        let mut inliers = Vec::with_capacity(data.len());
        let transform = refine(
            data,
            &hypothesis,
            cfg.threshold_m,
            cfg.refine_rounds,
            &mut inliers,
        )?;
        Ok(Estimate {
            diagnostics: Diagnostics {
                iterations: out.iterations,
                cost_evaluations: out.evaluations,
                final_cost: truncated_cost(data, &transform, cfg.threshold_m),
                residual_rms_m: residual_rms(data, &transform, &inliers),
                threshold_m: Some(cfg.threshold_m),
                elapsed: start.elapsed(),
            },
            transform,
            inliers,
        })
    }
}
