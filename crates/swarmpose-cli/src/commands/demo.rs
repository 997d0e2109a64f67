//! `swarmpose demo`: the main jobs on built-in data, with their default settings: the
//! paper's simulation (`simulate`) and visual odometry on the built-in synthetic stereo
//! sequence (`odometry` without a sequence).

use clap::{Args, FromArgMatches};

use crate::commands::{odometry, simulate};
use crate::error::CliError;

/// Arguments of `swarmpose demo` (none).
#[derive(Debug, Args)]
#[command(after_help = "\
Runs `swarmpose simulate` (writes out/simulate/) and then `swarmpose odometry` on the \
built-in synthetic stereo sequence (writes out/odometry/), each with its defaults. No data \
download is needed.")]
pub struct DemoArgs {}

/// A subcommand's arguments with every default, exactly as the command line gives them.
fn defaults<T: Args + FromArgMatches>(name: &'static str) -> Result<T, CliError> {
    let matches = T::augment_args(clap::Command::new(name))
        .try_get_matches_from([name])
        .map_err(|e| CliError::failure(format!("demo: default arguments of {name}: {e}")))?;
    T::from_arg_matches(&matches)
        .map_err(|e| CliError::failure(format!("demo: default arguments of {name}: {e}")))
}

/// Runs `demo`.
///
/// # Errors
/// Whatever the two jobs report.
pub fn run(_args: &DemoArgs) -> Result<(), CliError> {
    crate::streams::out(
        "== swarmpose simulate: the paper's section 6 simulation (figures 6 and 7) ==",
    )?;
    simulate::run(&defaults::<simulate::SimulateArgs>("simulate")?)?;
    crate::streams::out("")?;
    crate::streams::out("== swarmpose odometry: the built-in synthetic stereo sequence ==")?;
    odometry::run_command(&defaults::<odometry::OdometryArgs>("odometry")?)
}
