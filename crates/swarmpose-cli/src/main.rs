//! `swarmpose`: rigid 3D-3D pose estimation from matched points on the command line.
//!
//! Each subcommand lives in [`commands`]; every failure is printed as one line,
//! `swarmpose: error: ...`, with exit status 2 for bad usage or input, 1 for a run that
//! failed or an output that could not be written, 3 for a run that finished but whose
//! result is not usable (its outputs are written), 130/143 for a run stopped by
//! SIGINT/SIGTERM (odometry keeps the frames done), and 141 (quietly) when the reader of
//! standard output closed it.

#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

use std::process::ExitCode;

use clap::error::ErrorKind;
use clap::{CommandFactory, Parser, Subcommand};
use swarmpose_cli::error::CliError;
use swarmpose_cli::{batch, commands, error, streams};

/// Rigid 3D-3D pose estimation by particle swarm.
#[derive(Debug, Parser)]
#[command(name = "swarmpose", version, propagate_version = true)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Debug, Subcommand)]
enum Command {
    /// The main jobs on built-in data: `simulate`, then `odometry` on the built-in
    /// synthetic stereo sequence.
    Demo(commands::demo::DemoArgs),
    /// Reproduce the paper's simulation (section 6, figures 6 and 7): every estimator
    /// against noise and outliers; writes runs.csv, summary.md and the figures.
    Simulate(commands::simulate::SimulateArgs),
    /// Estimate the rigid motion dst = R src + t of a correspondence CSV; prints one
    /// JSON object.
    Register(commands::register::RegisterArgs),
    /// Run the estimators on a folder of scenario CSV + truth JSON files and print
    /// success, accuracy and time per cell as Markdown tables.
    Bench(commands::bench::BenchArgs),
    /// Stereo front end: the 3D-3D correspondences of two frames of a stereo sequence as
    /// a CSV for `register` (src = frame J, dst = frame I).
    Correspondences(commands::correspondences::CorrespondencesArgs),
    /// Compare an estimated trajectory with the ground truth: eq. (20) per frame and its
    /// RMS (Table I), ATE, RPE, final drift, KITTI segment errors.
    Evaluate(commands::evaluate::EvaluateArgs),
    /// Stereo visual odometry over a sequence: trajectory (KITTI, TUM), per-frame log,
    /// plots (figure 17) and, with ground truth, its evaluation.
    Odometry(Box<commands::odometry::OdometryArgs>),
    /// `odometry` over every sequence of a manifest, each into its own folder with a
    /// summary.json; shards, resumes, and `batch merge` makes one table of them.
    Batch(Box<batch::BatchArgs>),
}

fn run(cli: Cli) -> Result<(), CliError> {
    match cli.command {
        Command::Demo(args) => commands::demo::run(&args),
        Command::Simulate(args) => commands::simulate::run(&args),
        Command::Register(args) => commands::register::run(&args),
        Command::Bench(args) => commands::bench::run(&args),
        Command::Correspondences(args) => commands::correspondences::run(&args),
        Command::Evaluate(args) => commands::evaluate::run(&args),
        Command::Odometry(args) => commands::odometry::run_command(&args),
        Command::Batch(args) => batch::run(&args),
    }
}

/// Panics are bugs; still, report them as one line and no backtrace.
fn install_panic_hook() {
    std::panic::set_hook(Box::new(|info| {
        let what = info
            .payload()
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| info.payload().downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "unknown panic".to_owned());
        let at = info
            .location()
            .map(|l| format!(" at {}:{}", l.file(), l.line()))
            .unwrap_or_default();
        streams::print_error(&CliError::failure(format!(
            "internal error (a bug){at}: {what}"
        )));
    }));
}

fn main() -> ExitCode {
    install_panic_hook();
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) if matches!(e.kind(), ErrorKind::DisplayHelp | ErrorKind::DisplayVersion) => {
            // Help and version go to standard output with status 0.
            return match e.print() {
                Ok(()) => ExitCode::SUCCESS,
                Err(io) if io.kind() == std::io::ErrorKind::BrokenPipe => {
                    ExitCode::from(streams::EXIT_PIPE_CLOSED)
                }
                Err(_) => ExitCode::from(error::EXIT_FAILURE),
            };
        }
        Err(e) if e.kind() == ErrorKind::DisplayHelpOnMissingArgumentOrSubcommand => {
            let names: Vec<String> = Cli::command()
                .get_subcommands()
                .map(|c| c.get_name().to_owned())
                .filter(|n| n != "help")
                .collect();
            let err = CliError::usage(format!(
                "no subcommand given: use one of {} (try 'swarmpose --help')",
                names.join(", ")
            ));
            streams::print_error(&err);
            return ExitCode::from(err.code);
        }
        Err(e) => {
            let err = error::from_clap(&e);
            streams::print_error(&err);
            return ExitCode::from(err.code);
        }
    };
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            streams::print_error(&err);
            ExitCode::from(err.code)
        }
    }
}
