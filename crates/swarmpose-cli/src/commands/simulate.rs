//! `swarmpose simulate`: the paper's simulation (section 6, figures 6 and 7), the main
//! job on a built-in default.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use swarmpose_sim::experiment::{DEFAULT_FRACTIONS, DEFAULT_NOISE, DEFAULT_RUNS, DEFAULT_SEED};
use swarmpose_sim::{Experiment, OutlierMode, SimError, SimOptions, default_estimators, simulate};

use crate::error::CliError;

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
(times excepted).")]
pub struct SimulateArgs {
    /// Output folder (created).
    #[arg(long, value_name = "DIR", default_value = swarmpose_sim::simulate::DEFAULT_OUT)]
    pub out: PathBuf,

    /// Runs per noise level and outlier fraction.
    #[arg(long, value_name = "N", default_value_t = DEFAULT_RUNS)]
    pub runs: usize,

    /// Noise levels σ per axis, metres, comma separated.
    #[arg(long, value_name = "LIST", value_delimiter = ',', allow_negative_numbers = true,
          default_values_t = DEFAULT_NOISE)]
    pub noise: Vec<f64>,

    /// Outlier fractions in [0, 1), comma separated.
    #[arg(long, value_name = "LIST", value_delimiter = ',', allow_negative_numbers = true,
          default_values_t = DEFAULT_FRACTIONS)]
    pub fractions: Vec<f64>,

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
}

fn sim_error(e: &SimError) -> CliError {
    match e {
        SimError::InvalidConfig(_) | SimError::Io { .. } => CliError::usage(e.to_string()),
        _ => CliError::failure(e.to_string()),
    }
}

/// Runs `simulate`.
///
/// # Errors
/// Bad settings or an unwritable folder (before any work), or a failure while writing.
pub fn run(args: &SimulateArgs) -> Result<(), CliError> {
    let mut experiment = Experiment {
        noise_levels: args.noise.clone(),
        fractions: args.fractions.clone(),
        runs: args.runs,
        seed: args.seed,
        mode: match args.mode {
            Mode::Random => OutlierMode::Random,
            Mode::Structured => OutlierMode::Structured,
        },
        ..Experiment::default()
    };
    let mut out = args.out.clone();
    if args.quick {
        let quick = Experiment::quick();
        experiment.runs = quick.runs;
        experiment.fractions = quick.fractions;
        if out == std::path::Path::new(swarmpose_sim::simulate::DEFAULT_OUT) {
            out = PathBuf::from("out/simulate-quick");
        }
    }
    let opts = SimOptions {
        experiment,
        out_dir: out,
        export_dir: args.export.clone(),
        threads: args.threads,
        progress: true,
    };
    let outcome = simulate(&opts, &default_estimators()).map_err(|e| sim_error(&e))?;
    print!("{}", outcome.console);
    for f in &outcome.files {
        println!("wrote {}", f.display());
    }
    Ok(())
}
