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
    experiment.validate()?;
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
