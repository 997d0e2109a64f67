//! Settings of [`super::PsoEstimator`].

use crate::error::PoseError;
use crate::geometry::MIN_CORRESPONDENCES;
use crate::pso::{MAX_SWARM_SIZE, PsoConfig};
use crate::settings::{self, InvalidSetting, Path};

/// How `pso` chooses its inlier threshold when the data carry no per-point noise.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Threshold {
    /// A fixed δ, metres.
    Fixed(f64),
    /// Estimated from the data (see the module documentation).
    Auto,
}

impl std::fmt::Display for Threshold {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            Threshold::Fixed(d) => write!(f, "{d}"),
            Threshold::Auto => f.write_str("auto"),
        }
    }
}

/// Settings of [`super::PsoEstimator`]. Defaults in brackets.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct PsoEstimatorConfig {
    /// Inlier threshold δ on `|dst - (R src + t)|` [`Threshold::Auto`]. A fixed δ of about
    /// `3.4 σ` suits isotropic Gaussian noise of σ per axis. Ignored when the data carry a
    /// noise level per point.
    pub threshold: Threshold,
    /// First-pass δ of [`Threshold::Auto`] as a fraction of the scene scale (the median
    /// distance of the source points from their coordinate-wise median) \[0.04\]: the
    /// threshold scales with the data, whatever its unit.
    pub auto_initial_fraction: f64,
    /// Smallest δ [`Threshold::Auto`] may choose, as a fraction of the scene scale
    /// \[1e-5\].
    pub auto_min_fraction: f64,
    /// Largest δ [`Threshold::Auto`] may choose, as a fraction of the scene scale \[1\]
    /// (beyond, a motion is not identifiable from the points).
    pub auto_max_fraction: f64,
    /// δ_i = this · σ_i for per-point noise, and δ = this · σ̂ under
    /// [`Threshold::Auto`] [3.368 = sqrt of the 99 % quantile of χ²(3)].
    pub sigma_multiplier: f64,
    /// The swarm [16 particles, 30 iterations, α = 0.9, c = 1.5, stop after 5
    /// iterations without a better best].
    pub pso: PsoConfig,
    /// Particles started from graph triangles; the rest start uniformly \[8\].
    pub seeded_particles: usize,
    /// Points in the consistency graph; larger sets are sampled \[400\]. When the
    /// consensus found in a sample is not supported (see the module documentation), the
    /// sample doubles, up to `max_sample_growth` times this.
    pub max_points: usize,
    /// See `max_points` \[8\].
    pub max_sample_growth: usize,
    /// Most pairs scored per fitness evaluation \[256\].
    pub max_pairs: usize,
    /// Rounds of (inliers, SVD refit) at the end \[5\].
    pub refine_rounds: usize,
    /// Report a runner-up motion when its support reaches this fraction of the winner's
    /// [0.5]; 0 turns the check off.
    pub ambiguity_ratio: f64,
    /// Extra swarm searches on the same graph when the consensus holds fewer than
    /// `restart_below_ratio` of the correspondences (or none was found); the largest
    /// consensus wins \[3\]. Few inliers make the search hard, like RANSAC's sample count.
    pub restarts: usize,
    /// See `restarts` [0.2].
    pub restart_below_ratio: f64,
    /// Most rounds of the final Gaussian-uniform mixture refinement (step 6) \[10\]; 0
    /// ends with the hard-band SVD refit of step 4.
    pub mixture_rounds: usize,
    /// Without a noise model in the data, fit one that grows with the range along and
    /// across the viewing ray from each frame's origin (stereo, RGB-D, lidar), and use it
    /// (Mahalanobis fit and self-check, as with covariances) when the evidence prefers it
    /// to isotropic noise (see `ray_noise` in the module documentation) \[true\].
    pub range_noise: bool,
}

impl Default for PsoEstimatorConfig {
    fn default() -> Self {
        Self {
            threshold: Threshold::Auto,
            auto_initial_fraction: 0.04,
            auto_min_fraction: 1e-5,
            auto_max_fraction: 1.0,
            sigma_multiplier: 3.368,
            pso: PsoConfig::default()
                .with_swarm_size(16)
                .with_max_iterations(30)
                .with_stall_iterations(Some(5)),
            seeded_particles: 8,
            max_points: 400,
            max_sample_growth: 8,
            max_pairs: 256,
            refine_rounds: 5,
            ambiguity_ratio: 0.5,
            restarts: 3,
            restart_below_ratio: 0.2,
            mixture_rounds: 10,
            range_noise: true,
        }
    }
}

impl PsoEstimatorConfig {
    /// Sets a fixed δ (metres).
    #[must_use]
    pub fn with_threshold(mut self, threshold_m: f64) -> Self {
        self.threshold = Threshold::Fixed(threshold_m);
        self
    }

    /// Sets the swarm settings.
    #[must_use]
    pub fn with_pso(mut self, pso: PsoConfig) -> Self {
        self.pso = pso;
        self
    }

    /// Sets how many particles start from graph triangles.
    #[must_use]
    pub fn with_seeded_particles(mut self, n: usize) -> Self {
        self.seeded_particles = n;
        self
    }

    /// Sets the extra swarm searches made when the consensus is small (0 turns them off).
    #[must_use]
    pub fn with_restarts(mut self, restarts: usize) -> Self {
        self.restarts = restarts;
        self
    }

    /// Sets the rounds of the final mixture refinement (0 turns it off).
    #[must_use]
    pub fn with_mixture_rounds(mut self, rounds: usize) -> Self {
        self.mixture_rounds = rounds;
        self
    }

    /// Sets whether a range-dependent noise model is considered for plain coordinates.
    #[must_use]
    pub fn with_range_noise(mut self, on: bool) -> Self {
        self.range_noise = on;
        self
    }

    /// Sets the ambiguity ratio (0 turns the check off).
    #[must_use]
    pub fn with_ambiguity_ratio(mut self, ratio: f64) -> Self {
        self.ambiguity_ratio = ratio;
        self
    }

    pub(super) fn validate(&self) -> Result<(), PoseError> {
        Ok(self.check("")?)
    }

    /// Checks every setting's range, naming each below `prefix` (`estimator`) as in a
    /// run configuration: thresholds, fractions and the multiplier finite and above 0
    /// (`auto_min_fraction` at most `auto_max_fraction`), the ratios in `[0, 1]`, the
    /// swarm's ranges ([`PsoConfig::check`]) and the counts.
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of its range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        self.check_at(&Path::root(prefix))
    }

    /// [`Self::check`] below the path `at`.
    pub(crate) fn check_at(&self, at: &Path<'_>) -> Result<(), InvalidSetting> {
        let name = |n| at.child(n);
        if let Threshold::Fixed(d) = self.threshold {
            settings::positive(name("threshold"), d)?;
        }
        settings::positive(name("auto_initial_fraction"), self.auto_initial_fraction)?;
        settings::positive(name("auto_min_fraction"), self.auto_min_fraction)?;
        settings::not_below(
            name("auto_max_fraction"),
            self.auto_max_fraction,
            self.auto_min_fraction,
            "a finite fraction, at least auto_min_fraction",
        )?;
        settings::count_at_least(name("max_sample_growth"), self.max_sample_growth, 1)?;
        settings::positive(name("sigma_multiplier"), self.sigma_multiplier)?;
        self.pso.check_at(&name("pso"))?;
        settings::count_within(
            name("seeded_particles"),
            self.seeded_particles,
            0,
            MAX_SWARM_SIZE,
        )?;
        settings::count_at_least(name("max_points"), self.max_points, MIN_CORRESPONDENCES)?;
        settings::count_at_least(name("max_pairs"), self.max_pairs, 1)?;
        settings::count_at_least(name("refine_rounds"), self.refine_rounds, 1)?;
        settings::within(
            name("restart_below_ratio"),
            self.restart_below_ratio,
            0.0,
            1.0,
        )?;
        settings::within(name("ambiguity_ratio"), self.ambiguity_ratio, 0.0, 1.0)?;
        Ok(())
    }
}
