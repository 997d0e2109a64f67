//! `swarmpose batch MANIFEST --out DIR [--shard i/N] [--jobs J]`: `swarmpose odometry`
//! over every item of a manifest ([`manifest`]), each into `DIR/<item>/` with its
//! `summary.json` ([`item`]); `swarmpose batch merge DIR...`: one table of every item
//! ([`merge`]).

pub mod hashes;
pub mod item;
pub mod manifest;
pub mod merge;
pub mod table;

use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

use clap::{Args, Subcommand};

use self::item::{Outcome, run_item};
use self::manifest::{Item, Manifest, Shard};
use crate::error::{CliError, EXIT_FAILURE};
use crate::signals::StopRequest;
use crate::streams::out;

/// Name of the list of a batch's items in its output folder (for `merge`, to tell the
/// items missing).
pub const ITEMS: &str = "batch.json";

/// Arguments of `swarmpose batch`.
#[derive(Debug, Args)]
#[command(
    args_conflicts_with_subcommands = true,
    subcommand_negates_reqs = true,
    after_help = "\
MANIFEST is a TOML file (see README \"Many sequences\"): optional shared `config` (given as \
--config FILE) and `args` (more `swarmpose odometry` options), then one [[item]] per sequence \
folder or bag with `input`, an optional `name`, optional `args` and an optional \
`ground_truth` file (given as --ground-truth FILE: KITTI poses one a frame, or TUM poses \
matched by a bag's stamps). Each item runs as \
`swarmpose odometry INPUT --out DIR/<name> --quiet ARGS` would, in this process, and gets \
DIR/<name>/summary.json (status, exit code, frames, the evaluation's figures when the \
sequence has ground truth, time, and the hashes of the input and ground truth, the options \
and the version) \
and log.txt (its console output). A rerun skips the items whose summary says they finished \
with the same hashes and reruns the others (failed, stopped, missing). --shard i/N runs items \
i, i+N, i+2N, ... (from 1, in the manifest's order): N machines or array tasks with the same \
DIR share the work. One item's failure does not stop the others.

Exit status: 0 when every item of the shard finished usable; 1 when one or more did not \
(their summaries say why); 2 for a bad manifest or option (nothing runs); 130/143 when \
stopped by SIGINT/SIGTERM (the items being run stop between two frames; rerun to finish)."
)]
pub struct BatchArgs {
    #[command(subcommand)]
    pub command: Option<BatchCommand>,

    #[command(flatten)]
    pub run: RunArgs,
}

/// What `swarmpose batch` does besides running a manifest.
#[derive(Debug, Subcommand)]
pub enum BatchCommand {
    /// One table (CSV and Markdown) of every item of one or more batch output folders
    /// (the shards of a batch), or one simulation from `simulate --shard` folders.
    Merge(merge::MergeArgs),
}

/// Arguments of a batch run.
#[derive(Debug, Args)]
pub struct RunArgs {
    /// The manifest (TOML).
    #[arg(value_name = "MANIFEST", required = true)]
    pub manifest: Option<PathBuf>,

    /// Output folder: one folder per item (created).
    #[arg(long, value_name = "DIR", required = true)]
    pub out: Option<PathBuf>,

    /// Run the i-th of N shares of the items (from 1).
    #[arg(long, value_name = "i/N", default_value = "1/1")]
    pub shard: Shard,

    /// Items run at once (each on one thread unless its options say --threads 2).
    #[arg(long, value_name = "J", default_value_t = 1,
          value_parser = clap::value_parser!(u16).range(1..=256))]
    pub jobs: u16,
}

/// Runs `batch`.
///
/// # Errors
/// See the command's help (exit status).
pub fn run(args: &BatchArgs) -> Result<(), CliError> {
    match &args.command {
        Some(BatchCommand::Merge(m)) => merge::run(m),
        None => run_batch(&args.run),
    }
}

/// One line about an item's outcome.
fn outcome_line(name: &str, o: &Result<Outcome, CliError>) -> (String, bool) {
    match o {
        Ok(Outcome::Ran(s) | Outcome::Skipped(s)) => {
            let skipped = matches!(o, Ok(Outcome::Skipped(_)));
            let mut line = format!(
                "{name}: {}{}, {} frames ({} tracked)",
                s.status,
                if skipped {
                    " (done before: skipped)"
                } else {
                    ""
                },
                s.frames,
                s.tracked
            );
            if !skipped {
                line.push_str(&format!(", {:.1} s", s.time_s));
            }
            if let Some(m) = &s.message {
                line.push_str(&format!(": exit status {}: {m}", s.exit_code));
            }
            (line, s.status == item::STATUS_OK)
        }
        Ok(Outcome::Busy(why)) => (format!("{name}: not run: {why}"), false),
        Err(e) => (format!("{name}: not run: {}", e.message), false),
    }
}

/// Runs `items` into `out`, `jobs` at a time, until `stop` says so; each outcome in the
/// items' order (`None`: not started).
fn run_items(
    items: &[&Item],
    out: &Path,
    jobs: usize,
    stop: &StopRequest,
) -> Vec<Option<Result<Outcome, CliError>>> {
    let next = AtomicUsize::new(0);
    let results: Mutex<Vec<Option<Result<Outcome, CliError>>>> =
        Mutex::new(vec![None; items.len()]);
    std::thread::scope(|scope| {
        for _ in 0..jobs.min(items.len()) {
            let worker = || {
                loop {
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    if k >= items.len() || stop.exit_status().is_some() {
                        break;
                    }
                    let outcome = run_item(items[k], out);
                    let (line, _) = outcome_line(&items[k].name, &outcome);
                    // A closed standard output must not stop the items.
                    let _ = crate::streams::out(&line);
                    if let Ok(mut r) = results.lock() {
                        r[k] = Some(outcome);
                    }
                }
            };
            // The engine's stack as on the main thread.
            let spawned = std::thread::Builder::new()
                .stack_size(8 << 20)
                .spawn_scoped(scope, worker);
            if spawned.is_err() {
                break;
            }
        }
    });
    results.into_inner().unwrap_or_default()
}

/// Reads and checks the manifest at `path` (every item's options included: nothing runs
/// when one is bad), creates `out` and writes its [`ITEMS`].
///
/// # Errors
/// Exit status 2 for a bad manifest or option, 1 when `out` cannot be written.
pub fn prepare(path: &Path, out: &Path) -> Result<Manifest, CliError> {
    let manifest = Manifest::load(path)?;
    for item in &manifest.items {
        hashes::odometry_args(item, Path::new(".")).map_err(|e| {
            CliError::usage(format!("{}: item {}: {}", path.display(), item.name, e))
        })?;
    }
    std::fs::create_dir_all(out).map_err(|e| crate::output_file::write_error(out, &e))?;
    let mut names: Vec<&str> = manifest.items.iter().map(|i| i.name.as_str()).collect();
    names.sort_unstable();
    let list = serde_json::json!({ "items": names });
    crate::output_file::write_bytes(&out.join(ITEMS), format!("{list:#}\n").as_bytes())?;
    Ok(manifest)
}

fn run_batch(args: &RunArgs) -> Result<(), CliError> {
    let (Some(path), Some(dir)) = (&args.manifest, &args.out) else {
        return Err(CliError::usage("a MANIFEST and --out DIR are needed"));
    };
    let manifest = prepare(path, dir)?;
    let items = manifest.shard(args.shard);
    let stop = StopRequest::install();
    let outcomes = run_items(&items, dir, usize::from(args.jobs), &stop);
    let mut bad = Vec::new();
    let (mut ran, mut skipped, mut not_started) = (0, 0, 0);
    for (item, o) in items.iter().zip(&outcomes) {
        match o {
            None => not_started += 1,
            Some(o) => {
                match o {
                    Ok(Outcome::Skipped(_)) => skipped += 1,
                    _ => ran += 1,
                }
                if !outcome_line(&item.name, o).1 {
                    bad.push(item.name.as_str());
                }
            }
        }
    }
    out(&format!(
        "batch: shard {}/{}: {} item(s): {ran} run, {skipped} done before, {} did not \
         succeed; outputs in {}",
        args.shard.index,
        args.shard.count,
        items.len(),
        bad.len(),
        dir.display()
    ))?;
    if let Some(code) = stop.exit_status() {
        return Err(CliError {
            code,
            message: format!(
                "stopped by {} with {not_started} item(s) not started: rerun the same command \
                 to finish",
                stop.name().unwrap_or("a request")
            ),
        });
    }
    if bad.is_empty() {
        Ok(())
    } else {
        Err(CliError {
            code: EXIT_FAILURE,
            message: format!(
                "{} of {} item(s) did not succeed ({}); see their summary.json in {}",
                bad.len(),
                items.len(),
                bad.join(", "),
                dir.display()
            ),
        })
    }
}
