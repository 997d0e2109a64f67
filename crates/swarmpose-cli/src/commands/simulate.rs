//! `swarmpose simulate`: the paper's simulation (section 6, figures 6 and 7), the main
//! job on a built-in default.

use std::path::{Path, PathBuf};

use clap::{Args, ValueEnum};
use swarmpose_sim::experiment::{
    DEFAULT_FRACTIONS, DEFAULT_NOISE, DEFAULT_RUNS, DEFAULT_SEED, QUICK_FRACTIONS, QUICK_RUNS,
};
use swarmpose_sim::{
    Experiment, OutlierMode, Shard, SimError, SimOptions, default_estimators, simulate_shard,
};

use crate::error::CliError;
use crate::signals::StopRequest;

/// How outliers are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Mode {
    /// Wrong matches: the destination point is a uniform point of the scene box.
    Random,
    /// A moving object: the nearest-neighbour cluster of a random point moved rigidly.
    Structured,
}

/// Arguments of `swarmpose simulate`.
#[derive(Debug, Args)]
#[command(after_help = "\
Every noise level x outlier fraction x run x estimator (pso, pso-paper, svd, msac, each with \
the oracle threshold max(3.368 sigma, 0.01) m). Writes runs.csv, summary.md and the figures \
position_error, processing_time, rotation_error and success_rate as PNG and SVG into --out, \
and prints the summary table. The numbers are the same for a seed whatever the thread count \
(times excepted). At most 1 000 000 scenarios (noise levels x fractions x runs) and 1024 \
threads. SIGINT/SIGTERM stop it after the scenarios being run: runs.csv keeps the rows \
done, summary.md says where it stopped, and the status is 130/143.")]
pub struct SimulateArgs {
    /// Output folder (created).
    #[arg(long, value_name = "DIR", default_value = swarmpose_sim::simulate::DEFAULT_OUT)]
    pub out: PathBuf,

    /// Runs per noise level and outlier fraction [default: 50, or 10 with --quick].
    #[arg(long, value_name = "N")]
    pub runs: Option<usize>,

    /// Noise levels σ per axis, metres, comma separated.
    #[arg(long, value_name = "LIST", value_delimiter = ',', allow_negative_numbers = true,
          default_values_t = DEFAULT_NOISE)]
    pub noise: Vec<f64>,

    /// Outlier fractions in [0, 1), comma separated [default: 0,0.1,0.2,...,0.9, or
    /// 0,0.3,0.5,0.7,0.9 with --quick].
    #[arg(
        long,
        value_name = "LIST",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    pub fractions: Option<Vec<f64>>,

    /// How outliers are made.
    #[arg(long, value_enum, default_value_t = Mode::Random)]
    pub mode: Mode,

    /// Seed of run 0 (run i uses seed + i at every level).
    #[arg(long, value_name = "N", default_value_t = DEFAULT_SEED)]
    pub seed: u64,

    /// Worker threads [default: one per core].
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,

    /// A short run (10 runs, fractions 0, 0.3, 0.5, 0.7, 0.9) that takes seconds; the
    /// output goes to out/simulate-quick unless --out is given.
    #[arg(long)]
    pub quick: bool,

    /// Also write every scenario as CSV + truth JSON (gen_scenarios.py's format) here.
    #[arg(long, value_name = "DIR")]
    pub export: Option<PathBuf>,

    /// Run the i-th of N shares of the scenarios (from 1): runs.csv holds its rows and
    /// simulate-shard.txt describes it; `swarmpose batch merge DIR... --out DIR` makes the
    /// whole run's runs.csv, summary.md and figures from every share.
    #[arg(long, value_name = "i/N")]
    pub shard: Option<Shard>,
}

// Keep the help text's defaults in step with the library's.
const _: () = assert!(DEFAULT_RUNS == 50 && QUICK_RUNS == 10);
const _: () = assert!(DEFAULT_FRACTIONS.len() == 10 && QUICK_FRACTIONS.len() == 5);

/// Runs `simulate`.
///
/// # Errors
/// Bad settings (exit status 2, before any work), an unwritable folder (exit status 1,
/// before any work), or a failure while writing the results (exit status 1).
pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    let stop = StopRequest::install();
    // --quick sets the defaults; --runs and --fractions given explicitly still win.
    let base = if args.quick {
        Experiment::quick()
    } else {
        Experiment::default()
    };
    let experiment = Experiment {
        noise_levels: args.noise.clone(),
        fractions: args.fractions.clone().unwrap_or(base.fractions),
        runs: args.runs.unwrap_or(base.runs),
        seed: args.seed,
        mode: match args.mode {
            Mode::Random => OutlierMode::Random,
            Mode::Structured => OutlierMode::Structured,
        },
        ..Experiment::default()
    };
    let mut out = args.out.clone();
    if args.quick && out == Path::new(swarmpose_sim::simulate::DEFAULT_OUT) {
        out = PathBuf::from("out/simulate-quick");
    }
    let opts = SimOptions {
        experiment,
        out_dir: out,
        export_dir: args.export.clone(),
        threads: args.threads,
        progress: true,
    };
    // Settings and folders first: nothing runs when one is bad.
    // Bad settings are bad usage (2); a folder that cannot be written is an output that
    // cannot be written (1), as for every command.
    let sim_error = |e: SimError| match e {
        SimError::InvalidConfig(_) => CliError::usage(e.to_string()),
        other => CliError::failure(other.to_string()),
    };
    opts.check().map_err(sim_error)?;
    let stopped = || stop.exit_status().is_some();
    let shard = args.shard.unwrap_or(Shard::ALL);
    let outcome =
        simulate_shard(&opts, &default_estimators(), &stopped, shard).map_err(sim_error)?;
    let total = shard.len_of(opts.experiment.scenarios());
    let mut text = if outcome.scenarios_done < total {
        String::new()
    } else {
        outcome.console.clone()
    };
    for f in &outcome.files {
        text.push_str(&format!("wrote {}\n", f.display()));
    }
    crate::streams::out_text(&text)?;
    match stop.exit_status() {
        Some(code) if outcome.scenarios_done < total => Err(CliError {
            code,
            message: format!(
                "stopped by {} after {} of {total} scenarios: their rows are in {}",
                stop.name().unwrap_or("a request"),
                outcome.scenarios_done,
                opts.out_dir.join("runs.csv").display()
            ),
        }),
        _ => Ok(()),
    }
}
