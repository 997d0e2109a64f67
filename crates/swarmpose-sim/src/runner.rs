//! The experiment runner: every (noise, fraction, run) scenario through every estimator,
//! in parallel with rayon.
//!
//! Results do not depend on the thread count: each job regenerates its scenario from its
//! seeds, each estimator draws from a generator seeded by the run index only, and rows
//! are returned in job order (noise, fraction, run, estimator). Only the measured times
//! vary between runs of the program.

use std::time::Instant;

use rayon::prelude::*;
use swarmpose_core::Estimator;

use crate::error::SimError;
use crate::estimators::{EstimatorEntry, oracle_threshold};
use crate::experiment::Experiment;
use crate::metrics::{RunKey, RunRecord, evaluate};
use crate::outliers::splitmix;

/// Seed of the estimators' generator for run `run` of `experiment`.
#[must_use]
pub fn estimator_seed(experiment: &Experiment, run: usize) -> u64 {
    splitmix(experiment.run_seed(run) ^ 0x5EED_E571_4A70_0000)
}

/// Runs the experiment in the current rayon pool; `progress` is called once per finished
/// scenario (from worker threads).
///
/// # Errors
/// [`SimError::InvalidConfig`] for bad settings (checked before any work); generator
/// errors otherwise. An estimator failing on a scenario is not an error: its row records
/// the failure.
pub fn run_experiment(
    experiment: &Experiment,
    estimators: &[EstimatorEntry],
    progress: &(dyn Fn() + Sync),
) -> Result<Vec<RunRecord>, SimError> {
    run_experiment_until(experiment, estimators, progress, &|| false)
}

/// [`run_experiment`], stopping early when `stop` says so: a scenario not started by
/// then is skipped (one being run finishes), so the rows are those of the scenarios
/// done, in job order.
///
/// # Errors
/// As [`run_experiment`].
pub fn run_experiment_until(
    experiment: &Experiment,
    estimators: &[EstimatorEntry],
    progress: &(dyn Fn() + Sync),
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<Vec<RunRecord>, SimError> {
    run_experiment_shard(experiment, estimators, progress, stop, Shard::ALL)
}

/// A share `i/N` of a list of jobs: job `k` (from 0) belongs to shard `k mod N + 1`. An
/// experiment's jobs are its scenarios in job order (noise, fraction, run); a batch's
/// (`swarmpose batch --shard`) are its items.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// Which share, 1 to `count`.
    pub index: usize,
    /// How many shares.
    pub count: usize,
}

impl Shard {
    /// Every scenario.
    pub const ALL: Self = Self { index: 1, count: 1 };

    /// Whether scenario `k` belongs to this shard.
    #[must_use]
    pub fn holds(self, k: usize) -> bool {
        self.count > 0 && k % self.count + 1 == self.index
    }

    /// Scenarios of this shard among `total`.
    #[must_use]
    pub fn len_of(self, total: usize) -> usize {
        (0..self.count.min(total))
            .filter(|&k| self.holds(k))
            .map(|k| (total - k).div_ceil(self.count))
            .sum()
    }
}

impl std::str::FromStr for Shard {
    type Err = String;

    /// `i/N` with `1 <= i <= N`.
    fn from_str(s: &str) -> Result<Self, String> {
        let bad = || format!("'{s}' is not a shard i/N with 1 <= i <= N (for example 2/8)");
        let (i, n) = s.split_once('/').ok_or_else(bad)?;
        let index: usize = i.trim().parse().map_err(|_| bad())?;
        let count: usize = n.trim().parse().map_err(|_| bad())?;
        if index == 0 || index > count {
            return Err(bad());
        }
        Ok(Self { index, count })
    }
}

/// [`run_experiment_until`] on the scenarios of `shard` only: the rows of a whole run
/// that belong to those scenarios, in the same order and with the same values (times
/// excepted).
///
/// # Errors
/// As [`run_experiment`]; a shard outside `1..=count` is an invalid setting.
pub fn run_experiment_shard(
    experiment: &Experiment,
    estimators: &[EstimatorEntry],
    progress: &(dyn Fn() + Sync),
    stop: &(dyn Fn() -> bool + Sync),
    shard: Shard,
) -> Result<Vec<RunRecord>, SimError> {
    experiment.validate()?;
    if shard.index == 0 || shard.index > shard.count {
        return Err(SimError::InvalidConfig(format!(
            "shard {}/{}: i/N needs 1 <= i <= N",
            shard.index, shard.count
        )));
    }
    if estimators.is_empty() {
        return Err(SimError::InvalidConfig("no estimator to run".into()));
    }
    // One set of estimators per noise level (the threshold depends on σ).
    let built: Vec<(f64, Vec<Box<dyn Estimator>>)> = experiment
        .noise_levels
        .iter()
        .map(|&sigma| {
            let thr = oracle_threshold(sigma);
            (thr, estimators.iter().map(|e| (e.make)(thr)).collect())
        })
        .collect();
    let jobs: Vec<(usize, usize, usize)> = (0..experiment.noise_levels.len())
        .flat_map(|i| {
            (0..experiment.fractions.len())
                .flat_map(move |j| (0..experiment.runs).map(move |r| (i, j, r)))
        })
        .enumerate()
        .filter(|(k, _)| shard.holds(*k))
        .map(|(_, job)| job)
        .collect();
    let per_job: Vec<Vec<RunRecord>> = jobs
        .par_iter()
        .map(|&(i, j, run)| {
            if stop() {
                return Ok(Vec::new());
            }
            let noise = experiment.noise_levels[i];
            let fraction = experiment.fractions[j];
            let seed = experiment.run_seed(run);
            let scenario = experiment
                .scene
                .scenario(seed, noise, fraction, experiment.mode)?;
            let (thr, ests) = &built[i];
            let rows = ests
                .iter()
                .zip(estimators)
                .map(|(est, entry)| {
                    let start = Instant::now();
                    let result =
                        est.estimate_seeded(&scenario.data, estimator_seed(experiment, run));
                    let key = RunKey {
                        run,
                        estimator: &entry.name,
                        threshold_m: *thr,
                    };
                    evaluate(&scenario, key, &result, start.elapsed())
                })
                .collect();
            progress();
            Ok(rows)
        })
        .collect::<Result<_, SimError>>()?;
    Ok(per_job.into_iter().flatten().collect())
}
