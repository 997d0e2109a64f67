//! What an experiment covers: noise levels x outlier fractions x runs, one outlier mode.

use crate::error::SimError;
use crate::outliers::{OutlierMode, check_levels};
use crate::scenario::SceneSpec;

/// Default noise levels σ, metres (the paper's figure 6 panels).
pub const DEFAULT_NOISE: [f64; 4] = [0.0, 0.02, 0.05, 0.1];
/// Default outlier fractions, 0 to 0.9.
pub const DEFAULT_FRACTIONS: [f64; 10] = [0.0, 0.1, 0.2, 0.3, 0.4, 0.5, 0.6, 0.7, 0.8, 0.9];
/// Default runs per (noise, fraction), as the paper's 50.
pub const DEFAULT_RUNS: usize = 50;
/// Default first run seed (run `i` has seed `seed + i`), as `gen_scenarios.py`'s offset.
pub const DEFAULT_SEED: u64 = 1000;
/// `--quick` runs.
pub const QUICK_RUNS: usize = 10;
/// The most scenarios (noise levels x fractions x runs) an experiment may have: every
/// row of every run is kept in memory until the tables are written (a million scenarios
/// of four estimators is about 0.5 GB of rows and some hours of work). Before, a huge
/// `--runs` aborted on an allocation or overflowed the count.
pub const MAX_SCENARIOS: usize = 1_000_000;
/// `--quick` outlier fractions.
pub const QUICK_FRACTIONS: [f64; 5] = [0.0, 0.3, 0.5, 0.7, 0.9];

/// The grid of an experiment.
#[derive(Debug, Clone, PartialEq)]
pub struct Experiment {
    /// Noise levels σ, metres.
    pub noise_levels: Vec<f64>,
    /// Outlier fractions in `[0, 1)`.
    pub fractions: Vec<f64>,
    /// Runs per (noise, fraction).
    pub runs: usize,
    /// Seed of run 0; run `i` uses `seed + i` at every level (paired runs).
    pub seed: u64,
    /// How outliers are made.
    pub mode: OutlierMode,
    /// The scene and cameras.
    pub scene: SceneSpec,
}

impl Default for Experiment {
    fn default() -> Self {
        Self {
            noise_levels: DEFAULT_NOISE.to_vec(),
            fractions: DEFAULT_FRACTIONS.to_vec(),
            runs: DEFAULT_RUNS,
            seed: DEFAULT_SEED,
            mode: OutlierMode::Random,
            scene: SceneSpec::default(),
        }
    }
}

impl Experiment {
    /// The `--quick` grid: every default noise level, 5 fractions, 10 runs.
    #[must_use]
    pub fn quick() -> Self {
        Self {
            fractions: QUICK_FRACTIONS.to_vec(),
            runs: QUICK_RUNS,
            ..Self::default()
        }
    }

    /// Seed of run `run`.
    #[must_use]
    pub fn run_seed(&self, run: usize) -> u64 {
        self.seed.wrapping_add(run as u64)
    }

    /// Number of scenarios (noise x fraction x run).
    #[must_use]
    pub fn scenarios(&self) -> usize {
        self.noise_levels
            .len()
            .saturating_mul(self.fractions.len())
            .saturating_mul(self.runs)
    }

    /// Checks every setting, before any work.
    ///
    /// # Errors
    /// [`SimError::InvalidConfig`] naming the bad value: no noise level or fraction, a
    /// negative or non-finite noise, a fraction outside `[0, 1)`, zero runs, more than
    /// [`MAX_SCENARIOS`] scenarios, a bad scene.
    pub fn validate(&self) -> Result<(), SimError> {
        if self.noise_levels.is_empty() {
            return Err(SimError::InvalidConfig("no noise level given".into()));
        }
        if self.fractions.is_empty() {
            return Err(SimError::InvalidConfig("no outlier fraction given".into()));
        }
        if self.runs == 0 {
            return Err(SimError::InvalidConfig("runs must be at least 1".into()));
        }
        if self.scenarios() > MAX_SCENARIOS {
            return Err(SimError::InvalidConfig(format!(
                "{} runs x {} noise levels x {} fractions is over the {MAX_SCENARIOS} \
                 scenarios an experiment may have (every row is kept in memory)",
                self.runs,
                self.noise_levels.len(),
                self.fractions.len()
            )));
        }
        for &noise in &self.noise_levels {
            check_levels(noise, 0.0)?;
        }
        for &f in &self.fractions {
            check_levels(0.0, f)?;
        }
        self.scene.validate()
    }
}
