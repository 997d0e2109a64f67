//! The swarm itself.

use rand::RngExt;

use crate::error::PoseError;
use crate::rng::SeededRng;
use crate::settings::{self, InvalidSetting, Path};

/// Most particles a swarm may have (a million: tens of megabytes, and seconds of work
/// per estimate). More were allocated at once: 10^12 particles asked for 24 TB and
/// aborted the process.
pub const MAX_SWARM_SIZE: usize = 1_000_000;

/// Most iterations a swarm may run (a thousand times the default): an estimate is one
/// step of a run that a signal stops only between frames, so its work is bounded
/// (`--iterations 10^18 --stall none` ran for ever).
pub const MAX_ITERATIONS: usize = 100_000;

/// Settings of a [`ParticleSwarm`]. Defaults in brackets.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct PsoConfig {
    /// Number of particles \[32\].
    pub swarm_size: usize,
    /// Iteration budget after the initial evaluation \[100\].
    pub max_iterations: usize,
    /// Inertia `α` of eq. (5) [0.9]; with the random factor `φ0` its mean effect is `α/2`.
    pub inertia: f64,
    /// Acceleration `c` of eq. (5), shared by the cognitive and social terms [1.5].
    pub acceleration: f64,
    /// Velocity clamp as a fraction of the box width per dimension [0.25].
    pub velocity_clamp: f64,
    /// Stop after this many iterations without a better global best [None: run the whole
    /// budget].
    pub stall_iterations: Option<usize>,
}

impl Default for PsoConfig {
    fn default() -> Self {
        Self {
            swarm_size: 32,
            max_iterations: 100,
            inertia: 0.9,
            acceleration: 1.5,
            velocity_clamp: 0.25,
            stall_iterations: None,
        }
    }
}

impl PsoConfig {
    /// Sets the swarm size.
    #[must_use]
    pub fn with_swarm_size(mut self, n: usize) -> Self {
        self.swarm_size = n;
        self
    }

    /// Sets the iteration budget.
    #[must_use]
    pub fn with_max_iterations(mut self, n: usize) -> Self {
        self.max_iterations = n;
        self
    }

    /// Sets early stopping after `n` iterations without improvement.
    #[must_use]
    pub fn with_stall_iterations(mut self, n: Option<usize>) -> Self {
        self.stall_iterations = n;
        self
    }

    /// Checks the ranges: 1 to [`MAX_SWARM_SIZE`] particles, at most [`MAX_ITERATIONS`]
    /// iterations, finite non-negative
    /// coefficients, a clamp in `(0, 1]`.
    ///
    /// # Errors
    /// [`PoseError::InvalidConfig`] naming the bad field.
    pub fn validate(&self) -> Result<(), PoseError> {
        Ok(self.check("")?)
    }

    /// [`PsoConfig::validate`], naming each setting below `prefix` (`estimator.pso`) as
    /// in a run configuration.
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of its range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        self.check_at(&Path::root(prefix))
    }

    /// [`Self::check`] below the path `at`.
    pub(crate) fn check_at(&self, at: &Path<'_>) -> Result<(), InvalidSetting> {
        let name = |n| at.child(n);
        settings::count_within(name("swarm_size"), self.swarm_size, 1, MAX_SWARM_SIZE)?;
        settings::count_within(
            name("max_iterations"),
            self.max_iterations,
            0,
            MAX_ITERATIONS,
        )?;
        settings::at_least_zero(name("inertia"), self.inertia)?;
        settings::at_least_zero(name("acceleration"), self.acceleration)?;
        settings::ratio(name("velocity_clamp"), self.velocity_clamp)?;
        if let Some(n) = self.stall_iterations {
            settings::count_at_least(name("stall_iterations"), n, 1)?;
        }
        Ok(())
    }
}

/// What a run of the swarm found.
#[derive(Debug, Clone, PartialEq)]
pub struct PsoOutcome<const D: usize, S> {
    /// Best position seen (the global best `p_g`).
    pub best_position: [f64; D],
    /// Its score.
    pub best_score: S,
    /// Iterations run after the initial evaluation.
    pub iterations: usize,
    /// Fitness evaluations, the initial ones included.
    pub evaluations: u64,
    /// Every particle's best position `p_i` and its score, in particle order.
    pub personal_bests: Vec<([f64; D], S)>,
}

/// A particle swarm over a box `[lower, upper]` of `R^D`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ParticleSwarm {
    /// The settings.
    pub config: PsoConfig,
}

#[inline]
fn better<S: PartialOrd>(a: &S, b: &S) -> bool {
    matches!(a.partial_cmp(b), Some(std::cmp::Ordering::Less))
}

impl ParticleSwarm {
    /// A swarm with these settings.
    #[must_use]
    pub fn new(config: PsoConfig) -> Self {
        Self { config }
    }

    /// Minimises `fitness` over the box `lower..=upper` (positions are clamped to it).
    /// `initial` positions (clamped to the box) seed the first particles, which start at rest; the rest start uniformly in
    /// the box with velocities uniform in `±clamp`.
    ///
    /// A score that does not compare (NaN) never becomes a best.
    ///
    /// # Errors
    /// [`PoseError::InvalidConfig`] for bad settings or an empty/inverted/non-finite box.
    pub fn minimize<const D: usize, S, F>(
        &self,
        lower: [f64; D],
        upper: [f64; D],
        initial: &[[f64; D]],
        rng: &mut SeededRng,
        fitness: F,
    ) -> Result<PsoOutcome<D, S>, PoseError>
    where
        S: PartialOrd + Copy,
        F: FnMut(&[f64; D]) -> S,
    {
        let clamp = |x: &mut [f64; D]| {
            for d in 0..D {
                x[d] = x[d].clamp(lower[d], upper[d]);
            }
        };
        self.minimize_projected(lower, upper, initial, rng, clamp, fitness)
    }

    /// [`ParticleSwarm::minimize`] on a space whose own `project` maps every moved
    /// position back into it, instead of clamping to the box; the box then only sets
    /// where unseeded particles start and the velocity clamp. For a periodic space (such
    /// as rotation vectors, see [`crate::geometry::wrap_rotation_vector`]) this avoids the
    /// false minima that clamping creates on the box faces.
    ///
    /// # Errors
    /// As [`ParticleSwarm::minimize`].
    pub fn minimize_projected<const D: usize, S, F, P>(
        &self,
        lower: [f64; D],
        upper: [f64; D],
        initial: &[[f64; D]],
        rng: &mut SeededRng,
        project: P,
        mut fitness: F,
    ) -> Result<PsoOutcome<D, S>, PoseError>
    where
        S: PartialOrd + Copy,
        F: FnMut(&[f64; D]) -> S,
        P: Fn(&mut [f64; D]),
    {
        let cfg = &self.config;
        cfg.validate()?;
        if (0..D).any(|d| !(lower[d].is_finite() && upper[d].is_finite() && lower[d] < upper[d])) {
            return Err(PoseError::InvalidConfig(
                "search box must be finite with lower < upper".into(),
            ));
        }
        let mut vmax = [0.0; D];
        for d in 0..D {
            vmax[d] = cfg.velocity_clamp * (upper[d] - lower[d]);
        }
        let n = cfg.swarm_size;
        let mut pos = Vec::with_capacity(n);
        let mut vel = Vec::with_capacity(n);
        for i in 0..n {
            let mut x = [0.0; D];
            let mut v = [0.0; D];
            for d in 0..D {
                // A seeded particle is a hypothesis to refine: it starts at rest.
                (x[d], v[d]) = match initial.get(i) {
                    Some(p) => (p[d], 0.0),
                    None => (
                        rng.random_range(lower[d]..=upper[d]),
                        rng.random_range(-vmax[d]..=vmax[d]),
                    ),
                };
            }
            project(&mut x);
            pos.push(x);
            vel.push(v);
        }
        let mut best_pos = pos.clone();
        let mut best_score: Vec<S> = pos.iter().map(&mut fitness).collect();
        let mut evaluations = n as u64;
        let mut g = 0;
        for i in 1..n {
            if better(&best_score[i], &best_score[g]) {
                g = i;
            }
        }
        let (mut global_pos, mut global_score) = (best_pos[g], best_score[g]);
        let mut stall = 0;
        let mut iterations = 0;
        for _ in 0..cfg.max_iterations {
            iterations += 1;
            let mut improved = false;
            for i in 0..n {
                let (x, v) = (&mut pos[i], &mut vel[i]);
                for d in 0..D {
                    let (phi0, phi1, phi2): (f64, f64, f64) =
                        (rng.random(), rng.random(), rng.random());
                    let nv = cfg.inertia * phi0 * v[d]
                        + cfg.acceleration * phi1 * (best_pos[i][d] - x[d])
                        + cfg.acceleration * phi2 * (global_pos[d] - x[d]);
                    v[d] = nv.clamp(-vmax[d], vmax[d]);
                    x[d] += v[d];
                }
                project(x);
                let s = fitness(x);
                evaluations += 1;
                if better(&s, &best_score[i]) {
                    best_score[i] = s;
                    best_pos[i] = *x;
                    if better(&s, &global_score) {
                        global_score = s;
                        global_pos = *x;
                        improved = true;
                    }
                }
            }
            if improved {
                stall = 0;
            } else {
                stall += 1;
                if cfg.stall_iterations.is_some_and(|k| stall >= k) {
                    break;
                }
            }
        }
        Ok(PsoOutcome {
            best_position: global_pos,
            best_score: global_score,
            iterations,
            evaluations,
            personal_bests: best_pos.into_iter().zip(best_score).collect(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::seeded;
    use std::f64::consts::PI;

    fn sphere<const D: usize>(x: &[f64; D]) -> f64 {
        x.iter().map(|v| (v - 1.5) * (v - 1.5)).sum()
    }

    fn rastrigin<const D: usize>(x: &[f64; D]) -> f64 {
        10.0 * D as f64
            + x.iter()
                .map(|v| v * v - 10.0 * (2.0 * PI * v).cos())
                .sum::<f64>()
    }

    #[test]
    fn finds_sphere_minimum() {
        let swarm = ParticleSwarm::new(PsoConfig::default().with_max_iterations(200));
        let out = swarm
            .minimize([-10.0; 4], [10.0; 4], &[], &mut seeded(1), sphere::<4>)
            .expect("valid");
        assert!(out.best_score < 1e-8, "score {}", out.best_score);
        for v in out.best_position {
            assert!((v - 1.5).abs() < 1e-4);
        }
        assert_eq!(out.evaluations, 32 + 32 * 200);
    }

    #[test]
    fn finds_rastrigin_global_minimum_in_2d() {
        // Many local minima on an integer grid; the global one is 0 at the origin.
        let swarm = ParticleSwarm::new(
            PsoConfig::default()
                .with_swarm_size(40)
                .with_max_iterations(300),
        );
        let mut hits = 0;
        for seed in 0..20 {
            let out = swarm
                .minimize(
                    [-5.12; 2],
                    [5.12; 2],
                    &[],
                    &mut seeded(seed),
                    rastrigin::<2>,
                )
                .expect("valid");
            if out.best_score < 1e-6 {
                hits += 1;
            }
        }
        assert!(hits >= 18, "global minimum found in {hits}/20 runs");
    }

    #[test]
    fn same_seed_same_answer_and_stall_stops() {
        let cfg = PsoConfig::default().with_stall_iterations(Some(5));
        let swarm = ParticleSwarm::new(cfg);
        let a = swarm
            .minimize([-3.0; 3], [3.0; 3], &[], &mut seeded(9), |x: &[f64; 3]| {
                x[0].abs().floor()
            })
            .expect("valid");
        let b = swarm
            .minimize([-3.0; 3], [3.0; 3], &[], &mut seeded(9), |x: &[f64; 3]| {
                x[0].abs().floor()
            })
            .expect("valid");
        assert_eq!(a, b);
        assert!(a.iterations < 100, "stall stop did not trigger");
    }

    #[test]
    fn seeds_are_used_and_nan_never_wins() {
        let swarm = ParticleSwarm::new(PsoConfig::default().with_max_iterations(0));
        let out = swarm
            .minimize(
                [-1.0; 2],
                [1.0; 2],
                &[[0.25, -0.5]],
                &mut seeded(3),
                |x: &[f64; 2]| {
                    if x[0] == 0.25 { 0.0 } else { f64::NAN }
                },
            )
            .expect("valid");
        assert_eq!(out.best_position, [0.25, -0.5]);
    }

    #[test]
    fn bad_settings_are_errors() {
        let swarm = ParticleSwarm::new(PsoConfig::default().with_swarm_size(0));
        assert!(
            swarm
                .minimize([0.0], [1.0], &[], &mut seeded(0), |x: &[f64; 1]| x[0])
                .is_err()
        );
        let swarm = ParticleSwarm::default();
        assert!(
            swarm
                .minimize([1.0], [0.0], &[], &mut seeded(0), |x: &[f64; 1]| x[0])
                .is_err()
        );
        // 10^12 particles: refused, not allocated (the process aborted).
        let swarm = ParticleSwarm::new(PsoConfig::default().with_swarm_size(1_000_000_000_000));
        let e = swarm
            .minimize([0.0], [1.0], &[], &mut seeded(0), |x: &[f64; 1]| x[0])
            .expect_err("too many particles");
        assert!(
            e.to_string()
                .contains("swarm_size is 1000000000000: it must be from 1 to 1000000"),
            "{e}"
        );
    }
}
