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
//! For two correct matches `|e_k(R_true)| < δ_i + δ_j` whatever `t` is. The steps:
//!
//! 1. **Consistency graph.** On at most `max_points` hypothesis points (a random sample of
//!    larger sets), keep the pairs whose
//!    lengths agree, `| |b_k| - |a_k| | < δ_i + δ_j` (a rigid motion keeps lengths; a wrong
//!    match rarely does) and whose source length is at least `min(5δ, extent/10)`. Rank the
//!    pairs by their number of common neighbours (correct matches form a dense cluster) and
//!    score the best `max_pairs` ([`graph`]).
//! 2. **Swarm.** (Repeated up to `restarts` times on the same graph when the consensus
//!    found holds less than `restart_below_ratio` of the points; the largest wins.)
//!    Particles are rotation vectors mapped to unit quaternions
//!    ([`crate::geometry::rotation_from_particle`]). A particle's support is the number of
//!    scored pairs with `|e_k| < δ_i + δ_j`; the best particle has the most support, ties
//!    broken by the lower truncated cost. Part of the swarm starts at rotations solved from
//!    triangles of the graph (a top pair and a common neighbour).
//! 3. **Translation vote.** With the best rotation `R`, each point proposes
//!    `t_i = d_i - R s_i`; among the points in most supporting pairs, the proposal with the
//!    most others within `δ_i + δ_c` wins ([`vote`]).
//! 4. **SVD refinement.** Inliers are the points with `|d_i - (R s_i + t)| < δ_i`; Arun's
//!    SVD refits them until the set is stable. Fewer than 4 is
//!    [`PoseError::InsufficientSupport`].
//! 5. **Self-check** ([`check`]). The consensus must be more than what wrong matches agree
//!    on by chance at this threshold: with `p` the rate at which a row's source passes the
//!    test against another row's destination (measured on the data at the pose found) and
//!    `H` the rigid triangles of the graph, `k` inliers pass when `k - 3` Poisson(`n p`)
//!    chance agreements have tail probability below `0.01 / H`. Otherwise, while the
//!    graph held a sample, the sample doubles (up to `max_sample_growth` times
//!    `max_points`) and steps 1-5 run again; then the answer is
//!    [`PoseError::InsufficientSupport`] with the support needed, never a plain success.
//!
//!    **Noise model** (plain coordinates at a uniform δ, `range_noise`): before the
//!    self-check, the residuals choose between isotropic noise and noise that grows with
//!    the range along and across the viewing ray from each frame's origin (stereo,
//!    RGB-D, lidar), by a likelihood-ratio test and a test that no second motion is
//!    swallowed ([`super::ray_noise`]; sets larger than 2000 rows are sampled). When the
//!    range model wins, its covariances are attached and the estimate continues as with
//!    covariances (Mahalanobis fit, self-check on its test); the model is reported in
//!    [`Diagnostics::range_noise`].
//! 6. **Ambiguity.** If the points left over could hold a second motion with at least
//!    `ambiguity_ratio` of the winner's support (a moving object), steps 1-4 run on them
//!    (one swarm). The runner-up is reported ([`Diagnostics::runner_up`]) only when it
//!    passes the self-check and is a distinct motion: at its own inliers it moves the
//!    points by a median of more than 2 tolerances from where the winner puts them (far,
//!    noisy inliers the winner's band left out are the winner's motion again). A
//!    runner-up with more inliers than the winner becomes the winner.
//! 7. **Final refinement.** Without covariances, the final pose maximises the likelihood
//!    of a Gaussian (inliers) plus uniform (wrong matches) model of the residuals, by a
//!    few EM rounds of weighted SVD ([`super::mixture`]): inliers in the noise's tail
//!    count, wrong matches do not; the reported inliers are those within δ_i of that pose.
//!    With per-point covariances ([`Correspondences::with_noise_covariance`], anisotropic
//!    noise such as stereo's), a Gauss-Newton fit of the Mahalanobis residuals, gated at
//!    `sigma_multiplier²` in χ²(3) units ([`super::mahalanobis`]); with covariances this
//!    fit comes before the self-check, which then uses the Mahalanobis test.
//!
//! The tolerance δ_i is `sigma_multiplier · σ_i` when the correspondences carry a noise
//! level per point without covariances ([`Correspondences::with_noise_sigma`]), else the
//! fixed threshold, else (the default, [`Threshold::Auto`], also with covariances: the
//! search runs on the positions, as an isotropic bound as wide as a far stereo point's
//! depth noise would let wrong far matches outvote the consensus) it is estimated from
//! the data, in its own unit: a first pass at `auto_initial_fraction` of the scene scale
//! (the median distance of the source points from their coordinate-wise median; halved
//! up to three times while it finds no support), then `δ = sigma_multiplier · σ̂` with σ̂
//! from the median inlier residual, corrected for the band's truncation and for the 6
//! degrees of freedom the fit takes, refitted, at most doubling per round, never where
//! chance agreements would exceed a quarter of the consensus. Scaling every coordinate
//! by `k` scales δ by `k` and leaves the inliers unchanged.
//!
//! Degeneracy (coincident or collinear points) is judged on the core of each set (points
//! within 20 scene scales of its median) and on the inliers, so a single wild point (a
//! stereo point at near-zero disparity) neither spoils nor hides it.

mod check;
mod config;
mod graph;
mod range;
mod scale;
mod vote;

pub use config::{PsoEstimatorConfig, Threshold};

use std::f64::consts::PI;
use std::time::Instant;

use nalgebra::{Isometry3, Translation3};
use rand::seq::index::sample;

use super::consensus::{
    Tolerance, check_support, collect_inliers_within, refine_within, residual_rms,
    truncated_cost_within,
};

use super::mixture::{Mixture, refine_mixture};
use super::{Diagnostics, Estimate, Estimator, RunnerUp};
use crate::error::PoseError;
use crate::geometry::{
    Correspondences, MIN_CORRESPONDENCES, rotation_from_particle, spread, wrap_rotation_vector,
};
use crate::pso::ParticleSwarm;
use crate::rng::SeededRng;
use graph::PairGraph;
use range::Modelled;

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

/// Halvings of the first-pass δ tried by [`Threshold::Auto`] when a pass finds no support.
const AUTO_RETRIES: usize = 3;

/// One re-estimate of the automatic δ may at most multiply it by this (the residuals
/// within a tight band say little about how wide the noise is).
const AUTO_STEP: f64 = 2.0;

/// Most re-estimates of the automatic δ.
const AUTO_ROUNDS: usize = 8;

/// The automatic δ does not grow to where wrong matches would agree by chance with more
/// than this share of the consensus (at the current pose, measured as in [`check`]):
/// without it a weak consensus could widen its band until it swallows the scene.
const CHANCE_SHARE: f64 = 0.25;

/// A runner-up is a distinct motion when, at its own inliers, it moves the points by
/// more than this many tolerances δ_i from where the winner puts them (median).
const DISTINCT_MOTION: f64 = 2.0;

/// A motion with its inliers and the work it took.
struct Found {
    pose: Isometry3<f64>,
    inliers: Vec<usize>,
    iterations: usize,
    evaluations: u64,
}

impl PsoEstimator {
    /// Steps 1-4 on all of `data` with tolerance `tol`; with few inliers, steps 2-4 are
    /// repeated up to `restarts` times on the same graph and the largest consensus wins.
    fn find(
        &self,
        data: &Correspondences,
        tol: Tolerance<'_>,
        max_points: usize,
        rng: &mut SeededRng,
    ) -> Result<(Found, PairGraph), PoseError> {
        let cfg = &self.config;
        let n = data.len();
        let points: Vec<usize> = if n > max_points {
            let mut p = sample(rng, n, max_points).into_vec();
            p.sort_unstable();
            p
        } else {
            (0..n).collect()
        };
        let typical_tol = match tol {
            Tolerance::Uniform(d) => d,
            Tolerance::PerPoint(v) => v.iter().sum::<f64>() / v.len().max(1) as f64,
        };
        let min_len_m = (5.0 * typical_tol).min(0.1 * spread(data.src())[0]);
        let graph = PairGraph::build(data, points, tol, cfg.max_pairs, min_len_m);
        if graph.scored() == 0 {
            return Err(no_support());
        }
        let mut best = self.search(data, &graph, tol, rng);
        let few = |f: &Result<Found, PoseError>| {
            f.as_ref().map_or(true, |f| {
                (f.inliers.len() as f64) < cfg.restart_below_ratio * n as f64
            })
        };
        for _ in 0..cfg.restarts {
            if !few(&best) {
                break;
            }
            let next = self.search(data, &graph, tol, rng);
            best = match (best, next) {
                (Ok(a), Ok(b)) => {
                    let (work_i, work_e) =
                        (a.iterations + b.iterations, a.evaluations + b.evaluations);
                    let mut w = if b.inliers.len() > a.inliers.len()
                        || (b.inliers.len() == a.inliers.len()
                            && truncated_cost_within(data, &b.pose, tol)
                                < truncated_cost_within(data, &a.pose, tol))
                    {
                        b
                    } else {
                        a
                    };
                    w.iterations = work_i;
                    w.evaluations = work_e;
                    Ok(w)
                }
                (Ok(a), Err(_)) => Ok(a),
                (Err(_), next) => next,
            };
        }
        Ok((best?, graph))
    }

    /// Steps 2-4 on a built graph.
    fn search(
        &self,
        data: &Correspondences,
        graph: &PairGraph,
        tol: Tolerance<'_>,
        rng: &mut SeededRng,
    ) -> Result<Found, PoseError> {
        let cfg = &self.config;
        let seeds = graph.seeds(data, cfg.seeded_particles, rng);
        let swarm = ParticleSwarm::new(cfg.pso.clone());
        let out = swarm.minimize_projected(
            [-PI; 3],
            [PI; 3],
            &seeds,
            rng,
            wrap_rotation_vector,
            |x| graph.score(&rotation_from_particle(x)),
        )?;
        let rotation = rotation_from_particle(&out.best_position);
        let m = rotation.to_rotation_matrix().into_inner();
        let anchors = graph.anchors(&m, vote::ANCHORS);
        let t = vote::translation(data, &m, &anchors, tol).ok_or_else(no_support)?;
        let hypothesis = Isometry3::from_parts(Translation3::from(t), rotation);
        let mut inliers = Vec::with_capacity(data.len());
        let pose = refine_within(data, &hypothesis, tol, cfg.refine_rounds, &mut inliers)?;
        Ok(Found {
            pose,
            inliers,
            iterations: out.iterations,
            evaluations: out.evaluations,
        })
    }

    /// Re-estimates δ from the inlier residuals and refits (Threshold::Auto): σ̂ from the
    /// median inlier residual, corrected for the band's truncation and for the 6 degrees
    /// of freedom the fit takes, then `δ = sigma_multiplier · σ̂`, at most doubling per
    /// round and within `[auto_min_fraction, auto_max_fraction]` of the scene scale.
    fn auto_refit(
        &self,
        data: &Correspondences,
        found: &mut Found,
        first: f64,
        scene: f64,
        rng: &mut SeededRng,
    ) -> f64 {
        let cfg = &self.config;
        let (lo, hi) = (cfg.auto_min_fraction * scene, cfg.auto_max_fraction * scene);
        let mut delta = first;
        for _ in 0..AUTO_ROUNDS {
            let mut r: Vec<f64> = found
                .inliers
                .iter()
                .map(|&i| (data.dst()[i] - found.pose * data.src()[i]).norm())
                .collect();
            let median = scale::median(&mut r);
            // Fitted residuals are smaller than the noise: the fit took 6 of the 3n
            // degrees of freedom.
            let components = 3.0 * r.len() as f64;
            let dof = (components / (components - 6.0).max(1.0)).sqrt();
            let sigma = scale::truncated_sigma(median * dof, delta);
            let next = sigma
                .map_or(AUTO_STEP * delta, |s| cfg.sigma_multiplier * s)
                .min(AUTO_STEP * delta)
                .clamp(lo, hi);
            if next > delta {
                let (src, dst, pose) = (data.src(), data.dst(), found.pose);
                let p = check::chance_rate(
                    data.len(),
                    rng,
                    |i| pose * src[i],
                    |q, j| (dst[j] - q).norm_squared() < next * next,
                );
                if data.len() as f64 * p > CHANCE_SHARE * found.inliers.len() as f64 {
                    break;
                }
            }
            let mut inliers = Vec::with_capacity(data.len());
            match refine_within(
                data,
                &found.pose,
                Tolerance::Uniform(next),
                cfg.refine_rounds,
                &mut inliers,
            ) {
                Ok(pose) => {
                    found.pose = pose;
                    found.inliers = inliers;
                    let settled = (next - delta).abs() <= 0.05 * delta;
                    delta = next;
                    if settled {
                        break;
                    }
                }
                // Too tight to keep support: stay with the last δ.
                Err(_) => break,
            }
        }
        delta
    }

    /// Steps 1-4 with the first-pass tolerance, then (Threshold::Auto) the re-estimated
    /// δ, on a sample of `max_points`; the consensus must pass the self-check
    /// ([`check`]). Returns the motion, its graph and the tolerance.
    fn consensus(
        &self,
        data: &Correspondences,
        first: Tolerance<'_>,
        auto_scene: Option<f64>,
        max_points: usize,
        rng: &mut SeededRng,
    ) -> Result<(Found, PairGraph, Option<f64>, Modelled), PoseError> {
        let cfg = &self.config;
        let mut attempt = self.find(data, first, max_points, rng);
        if let (Some(scene), Tolerance::Uniform(mut d)) = (auto_scene, first) {
            // A generous first pass can drown very few inliers in chance agreements:
            // retry with smaller δ before giving up.
            for _ in 0..AUTO_RETRIES {
                if attempt.is_ok() || d / 2.0 < cfg.auto_min_fraction * scene {
                    break;
                }
                d /= 2.0;
                attempt = self.find(data, Tolerance::Uniform(d), max_points, rng);
            }
            let (mut found, graph) = attempt?;
            let delta = self.auto_refit(data, &mut found, d, scene, rng);
            let modelled = self.range_model(data, &found, delta, rng);
            let checked_on = modelled.as_ref().map_or(data, |m| &m.0);
            self.checked(
                checked_on,
                &mut found,
                &graph,
                Tolerance::Uniform(delta),
                rng,
            )?;
            return Ok((found, graph, Some(delta), modelled));
        }
        let (mut found, graph) = attempt?;
        let modelled = match first {
            Tolerance::Uniform(d) => self.range_model(data, &found, d, rng),
            Tolerance::PerPoint(_) => None,
        };
        let checked_on = modelled.as_ref().map_or(data, |m| &m.0);
        self.checked(checked_on, &mut found, &graph, first, rng)?;
        Ok((found, graph, None, modelled))
    }

    /// When the runner-up holds more inliers than the winner (the swarm settled on a
    /// smaller motion, such as a moving object), it becomes the winner, refitted on all
    /// the data; the old winner is then the runner-up if its support still reaches
    /// `ambiguity_ratio` of the new winner's. Returns the runner-up to report.
    fn larger_consensus_wins(
        &self,
        data: &Correspondences,
        found: &mut Found,
        runner_up: RunnerUp,
        tol: Tolerance<'_>,
    ) -> Option<RunnerUp> {
        if runner_up.inliers.len() <= found.inliers.len() {
            return Some(runner_up);
        }
        let mut inliers = Vec::with_capacity(data.len());
        let Ok(pose) = refine_within(
            data,
            &runner_up.transform,
            tol,
            self.config.refine_rounds,
            &mut inliers,
        ) else {
            return Some(runner_up);
        };
        let old = RunnerUp {
            transform: std::mem::replace(&mut found.pose, pose),
            inliers: std::mem::replace(&mut found.inliers, inliers),
        };
        let needed = self.config.ambiguity_ratio * found.inliers.len() as f64;
        (old.inliers.len() as f64 >= needed).then_some(old)
    }

    /// Step 6: with per-point covariances, the Mahalanobis refinement of
    /// [`super::mahalanobis`] (its inliers pass the χ²(3) gate `sigma_multiplier²`);
    /// otherwise the mixture refinement of [`super::mixture`] (the inliers stay those
    /// within δ_i of the refined pose). Keeps `found` when the refined pose loses the
    /// support.
    fn polish(&self, data: &Correspondences, found: &mut Found, tol: Tolerance<'_>) {
        let cfg = &self.config;
        if data.noise_covariance().is_some() {
            // Done with the self-check (`checked`).
            return;
        }
        if cfg.mixture_rounds == 0 {
            return;
        }
        let settings = Mixture {
            multiplier: cfg.sigma_multiplier,
            rounds: cfg.mixture_rounds,
        };
        let mut weights = Vec::with_capacity(data.len());
        let pose = refine_mixture(data, &found.pose, tol, settings, &mut weights);
        let mut inliers = Vec::with_capacity(data.len());
        collect_inliers_within(data, &pose, tol, &mut inliers);
        if check_support(data, &inliers).is_ok() {
            found.pose = pose;
            found.inliers = inliers;
        }
    }

    /// Step 5: a second motion among the points the first left over, if it could reach
    /// `ambiguity_ratio` of the winner's support.
    fn runner_up(
        &self,
        data: &Correspondences,
        winner: &Found,
        graph: &PairGraph,
        tol: Tolerance<'_>,
        rng: &mut SeededRng,
    ) -> Option<RunnerUp> {
        let cfg = &self.config;
        if cfg.ambiguity_ratio <= 0.0 {
            return None;
        }
        let needed = ((cfg.ambiguity_ratio * winner.inliers.len() as f64).ceil() as usize)
            .max(MIN_CORRESPONDENCES);
        let mut taken = vec![false; data.len()];
        for &i in &winner.inliers {
            taken[i] = true;
        }
        let rest: Vec<usize> = (0..data.len()).filter(|&i| !taken[i]).collect();
        // A rigid cluster of k points gives its pairs about k - 2 common neighbours; the
        // graph sees a sample of the points, so be generous before paying for a search.
        let sampled = graph_fraction(data.len(), cfg.max_points);
        if rest.len() < needed
            || (graph.max_common_outside(&taken) as f64) < 0.5 * sampled * needed as f64 - 2.0
        {
            return None;
        }
        let sub = data.select(&rest);
        let sub_tol: Vec<f64> = rest.iter().map(|&i| tol.at(i)).collect();
        let sub_tol = Tolerance::PerPoint(&sub_tol);
        // One swarm search: a second motion with comparable support is found without
        // the restarts that a small consensus needs.
        let quick = PsoEstimator::new(PsoEstimatorConfig {
            restarts: 0,
            ..cfg.clone()
        });
        let (found, sub_graph) = quick.find(&sub, sub_tol, cfg.max_points, rng).ok()?;
        if found.inliers.len() < needed {
            return None;
        }
        // A second motion, not chance agreement among the left-overs ...
        let sub_triangles = check::triangles(sub.len(), &sub_graph);
        self.check(&sub, &found, sub_tol, sub_triangles, rng).ok()?;
        // ... nor the winner's motion again on points it left out (far, noisy inliers):
        // at the runner-up's inliers the two motions must differ by several tolerances.
        let mut moved: Vec<f64> = found
            .inliers
            .iter()
            .map(|&k| {
                let s = &sub.src()[k];
                (winner.pose * s - found.pose * s).norm() / sub_tol.at(k)
            })
            .collect();
        (scale::median(&mut moved) > DISTINCT_MOTION).then(|| RunnerUp {
            transform: found.pose,
            inliers: found.inliers.iter().map(|&k| rest[k]).collect(),
        })
    }
}

/// The error of a search that found no motion.
fn no_support() -> PoseError {
    PoseError::InsufficientSupport {
        support: 0,
        needed: MIN_CORRESPONDENCES,
    }
}

/// Fraction of the points that the graph holds.
fn graph_fraction(n: usize, max_points: usize) -> f64 {
    if n <= max_points {
        1.0
    } else {
        max_points as f64 / n as f64
    }
}

impl Estimator for PsoEstimator {
    fn name(&self) -> &'static str {
        "pso"
    }

    fn estimate(&self, data: &Correspondences, rng: &mut SeededRng) -> Result<Estimate, PoseError> {
        let start = Instant::now();
        let cfg = &self.config;
        cfg.validate()?;
        // Degeneracy is judged on the inliers the estimate rests on (a single point at
        // 1e10 m must not make a good set look collinear).
        data.require(MIN_CORRESPONDENCES)?;
        let scene = scale::check_core(data.src(), "source")?;
        scale::check_core(data.dst(), "destination")?;
        // With covariances, the search runs on the points' positions (as without a noise
        // model) and the Mahalanobis refinement of step 6 takes the covariances: an
        // isotropic bound as wide as a far point's depth noise would let wrong far
        // matches outvote the consensus.
        let per_point: Option<Vec<f64>> = match (data.noise_covariance(), data.noise_sigma()) {
            (None, Some(s)) => Some(s.iter().map(|v| cfg.sigma_multiplier * v).collect()),
            _ => None,
        };
        let (first_tol, auto_scene) = match (&per_point, cfg.threshold) {
            (Some(v), _) => (Tolerance::PerPoint(v), None),
            (None, Threshold::Fixed(d)) => (Tolerance::Uniform(d), None),
            (None, Threshold::Auto) => (
                Tolerance::Uniform(cfg.auto_initial_fraction * scene),
                Some(scene),
            ),
        };
        // Grow the sample while its consensus is not supported.
        let n = data.len();
        let mut max_points = cfg.max_points;
        let (mut found, graph, auto_delta, modelled) = loop {
            match self.consensus(data, first_tol, auto_scene, max_points, rng) {
                Ok(ok) => break ok,
                Err(e)
                    if max_points >= n || max_points >= cfg.max_points * cfg.max_sample_growth =>
                {
                    return Err(e);
                }
                Err(_) => max_points = (2 * max_points).min(n),
            }
        };
        // Plain coordinates whose residuals chose the range-dependent noise model carry
        // its covariances from here on.
        let data = modelled.as_ref().map_or(data, |m| &m.0);
        let (tol, threshold_m) = match (auto_delta, cfg.threshold) {
            (Some(d), _) => (Tolerance::Uniform(d), Some(d)),
            (None, Threshold::Fixed(d)) if per_point.is_none() => (first_tol, Some(d)),
            (None, _) => (first_tol, None),
        };
        let mut runner_up = self.runner_up(data, &found, &graph, tol, rng);
        if let Some(r) = runner_up.take() {
            runner_up = self.larger_consensus_wins(data, &mut found, r, tol);
        }
        self.polish(data, &mut found, tol);
        Ok(Estimate {
            diagnostics: Diagnostics {
                iterations: found.iterations,
                cost_evaluations: found.evaluations,
                final_cost: truncated_cost_within(data, &found.pose, tol),
                residual_rms_m: residual_rms(data, &found.pose, &found.inliers),
                threshold_m,
                elapsed: start.elapsed(),
                runner_up,
                range_noise: modelled.as_ref().map(|m| m.1),
            },
            transform: found.pose,
            inliers: found.inliers,
        })
    }
}

#[cfg(test)]
mod tests;
