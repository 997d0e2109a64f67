//! The whole job behind `swarmpose simulate`: check the settings and folders, optionally
//! export the scenarios, run every estimator with a progress bar, write `runs.csv`,
//! `summary.md` and the figures.

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rayon::prelude::*;

use crate::error::SimError;
use crate::estimators::EstimatorEntry;
use crate::experiment::Experiment;
use crate::export::{scenario_name, write_scenario};
use crate::metrics::RunRecord;
use crate::output::ensure_writable_dir;
use crate::report::console_summary;
pub use crate::results::write_results;
use crate::runner::{Shard, run_experiment_shard};
use crate::stats::Summary;

/// Default output folder.
pub const DEFAULT_OUT: &str = "out/simulate";

/// The most worker threads accepted (a thousand times this machine's cores is no use,
/// and each thread reserves a stack).
pub const MAX_THREADS: usize = 1024;

/// Settings of a simulation job.
#[derive(Debug, Clone, PartialEq)]
pub struct SimOptions {
    /// The grid.
    pub experiment: Experiment,
    /// Where `runs.csv`, `summary.md` and the figures go (created).
    pub out_dir: PathBuf,
    /// Also write every scenario as CSV + truth JSON here.
    pub export_dir: Option<PathBuf>,
    /// Worker threads (`None`: rayon's default, one per core).
    pub threads: Option<usize>,
    /// Show a progress bar on standard error (hidden when it is not a terminal).
    pub progress: bool,
}

impl Default for SimOptions {
    fn default() -> Self {
        Self {
            experiment: Experiment::default(),
            out_dir: PathBuf::from(DEFAULT_OUT),
            export_dir: None,
            threads: None,
            progress: true,
        }
    }
}

/// What a job produced.
#[derive(Debug, Clone)]
pub struct SimOutcome {
    /// Every run.
    pub rows: Vec<RunRecord>,
    /// The aggregates.
    pub summary: Summary,
    /// Files written, in order.
    pub files: Vec<PathBuf>,
    /// The short table for the terminal.
    pub console: String,
    /// Wall time of the estimation phase.
    pub wall: Duration,
    /// Threads used.
    pub threads: usize,
    /// Scenarios run: all of the experiment's, or fewer when it was stopped
    /// ([`simulate_until`]).
    pub scenarios_done: usize,
}

impl SimOptions {
    /// Checks the settings and that the folders can be written, creating them.
    ///
    /// # Errors
    /// [`SimError::InvalidConfig`] or [`SimError::Io`].
    pub fn check(&self) -> Result<(), SimError> {
        self.experiment.validate()?;
        if let Some(n) = self.threads
            && !(1..=MAX_THREADS).contains(&n)
        {
            return Err(SimError::InvalidConfig(format!(
                "threads must be 1 to {MAX_THREADS}, got {n}"
            )));
        }
        ensure_writable_dir(&self.out_dir)?;
        if let Some(dir) = &self.export_dir {
            ensure_writable_dir(dir)?;
        }
        Ok(())
    }
}

fn bar(len: usize, show: bool, message: &str) -> ProgressBar {
    let target = if show {
        ProgressDrawTarget::stderr()
    } else {
        ProgressDrawTarget::hidden()
    };
    let pb = ProgressBar::with_draw_target(Some(len as u64), target);
    if let Ok(style) = ProgressStyle::with_template(
        "{msg} [{elapsed_precise}] {wide_bar} {pos}/{len} scenarios (eta {eta})",
    ) {
        pb.set_style(style);
    }
    pb.set_message(message.to_owned());
    pb
}

/// Writes every scenario of the experiment into `dir` (until `stop` says so).
fn export_all(
    exp: &Experiment,
    dir: &Path,
    show: bool,
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<(), SimError> {
    let jobs: Vec<(f64, f64, usize)> = exp
        .noise_levels
        .iter()
        .flat_map(|&n| {
            exp.fractions
                .iter()
                .flat_map(move |&f| (0..exp.runs).map(move |r| (n, f, r)))
        })
        .collect();
    let pb = bar(jobs.len(), show, "export");
    jobs.par_iter().try_for_each(|&(noise, f, run)| {
        if stop() {
            return Ok(());
        }
        let s = exp.scene.scenario(exp.run_seed(run), noise, f, exp.mode)?;
        write_scenario(dir, &scenario_name(exp.mode, noise, f, run), &s)?;
        pb.inc(1);
        Ok::<(), SimError>(())
    })?;
    pb.finish_and_clear();
    Ok(())
}

/// Runs the job (see the module documentation) with `estimators`.
///
/// # Errors
/// Bad settings or unwritable folders before any work ([`SimOptions::check`]); write or
/// plot failures after.
pub fn simulate(opts: &SimOptions, estimators: &[EstimatorEntry]) -> Result<SimOutcome, SimError> {
    simulate_until(opts, estimators, &|| false)
}

/// [`simulate`], stopping early when `stop` says so (a signal): the scenarios not
/// started are skipped, and `runs.csv` holds the rows of those done, with a
/// `summary.md` that says the run was stopped and where (no figures: their cells
/// would be partly empty). [`SimOutcome::scenarios_done`] tells how far it got.
///
/// # Errors
/// As [`simulate`].
pub fn simulate_until(
    opts: &SimOptions,
    estimators: &[EstimatorEntry],
    stop: &(dyn Fn() -> bool + Sync),
) -> Result<SimOutcome, SimError> {
    simulate_shard(opts, estimators, stop, Shard::ALL)
}

/// [`simulate_until`] on the scenarios of `shard` only ([`Shard`]): with more than one
/// shard, `runs.csv` holds the shard's rows and `simulate-shard.txt` describes it, for
/// [`crate::shard::merge_shards`] to make the whole run's files from every shard (no
/// summary or figures here).
///
/// # Errors
/// As [`simulate`]; `export_dir` with more than one shard is an invalid setting.
pub fn simulate_shard(
    opts: &SimOptions,
    estimators: &[EstimatorEntry],
    stop: &(dyn Fn() -> bool + Sync),
    shard: Shard,
) -> Result<SimOutcome, SimError> {
    opts.check()?;
    if shard != Shard::ALL && opts.export_dir.is_some() {
        return Err(SimError::InvalidConfig(
            "export the scenarios from a run without --shard".into(),
        ));
    }
    if estimators.is_empty() {
        return Err(SimError::InvalidConfig("no estimator to run".into()));
    }
    let mut builder = rayon::ThreadPoolBuilder::new();
    if let Some(n) = opts.threads {
        builder = builder.num_threads(n);
    }
    let pool = builder
        .build()
        .map_err(|e| SimError::ThreadPool(e.to_string()))?;
    let exp = &opts.experiment;
    let (rows, wall) = pool.install(|| {
        if let Some(dir) = &opts.export_dir {
            export_all(exp, dir, opts.progress, stop)?;
        }
        let pb = bar(shard.len_of(exp.scenarios()), opts.progress, "simulate");
        let start = Instant::now();
        let rows = run_experiment_shard(exp, estimators, &|| pb.inc(1), stop, shard)?;
        pb.finish_and_clear();
        Ok::<_, SimError>((rows, start.elapsed()))
    })?;
    let threads = pool.current_num_threads();
    let scenarios_done = rows.len() / estimators.len();
    let (summary, files, console) = if shard == Shard::ALL {
        let (summary, files) =
            write_results(exp, &rows, estimators.len(), wall, threads, &opts.out_dir)?;
        let console = console_summary(&summary);
        (summary, files, console)
    } else {
        let part = crate::shard::ShardRun {
            shard,
            scenarios_done,
            wall,
            threads,
        };
        let files = crate::shard::write_shard(exp, &part, &rows, &opts.out_dir)?;
        (Summary::new(exp, &rows), files, String::new())
    };
    Ok(SimOutcome {
        console,
        rows,
        summary,
        files,
        wall,
        threads,
        scenarios_done,
    })
}
