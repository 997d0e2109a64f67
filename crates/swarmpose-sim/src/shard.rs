//! A simulation split into shards (`swarmpose simulate --shard i/N`, on N machines or
//! array tasks) and merged back: each shard writes the rows of its scenarios
//! ([`crate::runner::Shard`]) to `runs.csv` and describes itself in
//! `simulate-shard.txt`; [`merge_shards`] puts the rows of every shard back in the whole
//! run's order and writes `runs.csv`, `summary.md` and the figures as one run does.

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::error::SimError;
use crate::experiment::Experiment;
use crate::metrics::RunRecord;
use crate::outliers::OutlierMode;
use crate::output::write_file;
use crate::results::write_results;
use crate::runner::Shard;
use crate::runs_csv::{parse_runs_csv, runs_csv};
use crate::stats::Summary;

/// Name of a shard's description in its folder.
pub const SHARD_FILE: &str = "simulate-shard.txt";

/// How a shard's run went.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ShardRun {
    /// Which shard.
    pub shard: Shard,
    /// Scenarios run (fewer than the shard's when stopped).
    pub scenarios_done: usize,
    /// Wall time.
    pub wall: Duration,
    /// Worker threads.
    pub threads: usize,
}

fn list(values: &[f64]) -> String {
    values
        .iter()
        .map(f64::to_string)
        .collect::<Vec<_>>()
        .join(",")
}

/// The lines that must be the same in every shard of one simulation.
fn identity(exp: &Experiment, count: usize) -> String {
    format!(
        "shards {count}\nnoise {}\nfractions {}\nruns {}\nseed {}\nmode {}\nscene {:?}\n",
        list(&exp.noise_levels),
        list(&exp.fractions),
        exp.runs,
        exp.seed,
        exp.mode.name(),
        exp.scene
    )
}

/// Writes `runs.csv` (the shard's rows) and [`SHARD_FILE`] into `dir`.
///
/// # Errors
/// [`SimError::Io`].
pub fn write_shard(
    exp: &Experiment,
    run: &ShardRun,
    rows: &[RunRecord],
    dir: &Path,
) -> Result<Vec<PathBuf>, SimError> {
    let csv = dir.join("runs.csv");
    let text = runs_csv(rows).map_err(|e| SimError::io(&csv, e.into()))?;
    write_file(&csv, text)?;
    let mut text = String::from(
        "# swarmpose simulate --shard: one share of a simulation (swarmpose batch merge)\n",
    );
    text.push_str(&identity(exp, run.shard.count));
    let _ = write!(
        text,
        "shard {}\nscenarios {}\ndone {}\nwall_s {}\nthreads {}\n",
        run.shard.index,
        run.shard.len_of(exp.scenarios()),
        run.scenarios_done,
        run.wall.as_secs_f64(),
        run.threads
    );
    let desc = dir.join(SHARD_FILE);
    write_file(&desc, text)?;
    Ok(vec![csv, desc])
}

/// A shard read back.
struct ShardDir {
    dir: PathBuf,
    identity: String,
    experiment: Experiment,
    run: ShardRun,
    shard_scenarios: usize,
    rows: Vec<RunRecord>,
}

fn parse_list(v: &str) -> Result<Vec<f64>, String> {
    v.split(',')
        .map(|x| x.parse().map_err(|_| format!("'{x}' is not a number")))
        .collect()
}

/// Reads the shard in `dir`.
fn read_shard(dir: &Path) -> Result<ShardDir, String> {
    let text =
        std::fs::read_to_string(dir.join(SHARD_FILE)).map_err(|e| format!("{SHARD_FILE}: {e}"))?;
    let get = |key: &str| {
        text.lines()
            .find_map(|l| l.strip_prefix(key)?.strip_prefix(' '))
            .ok_or_else(|| format!("{SHARD_FILE}: no '{key}'"))
    };
    let num = |key: &str| -> Result<usize, String> {
        get(key)?
            .parse()
            .map_err(|_| format!("{SHARD_FILE}: '{key}' is not a count"))
    };
    let mode = match get("mode")? {
        "random" => OutlierMode::Random,
        "structured" => OutlierMode::Structured,
        m => return Err(format!("{SHARD_FILE}: unknown mode '{m}'")),
    };
    let experiment = Experiment {
        noise_levels: parse_list(get("noise")?)?,
        fractions: parse_list(get("fractions")?)?,
        runs: num("runs")?,
        seed: get("seed")?.parse().map_err(|_| "bad seed".to_owned())?,
        mode,
        ..Experiment::default()
    };
    let count = num("shards")?;
    let run = ShardRun {
        shard: Shard {
            index: num("shard")?,
            count,
        },
        scenarios_done: num("done")?,
        wall: Duration::from_secs_f64(get("wall_s")?.parse().unwrap_or(0.0)),
        threads: num("threads")?,
    };
    let csv =
        std::fs::read_to_string(dir.join("runs.csv")).map_err(|e| format!("runs.csv: {e}"))?;
    let rows = parse_runs_csv(&csv).map_err(|e| format!("runs.csv: {e}"))?;
    Ok(ShardDir {
        dir: dir.to_owned(),
        identity: identity(&experiment, count),
        shard_scenarios: num("scenarios")?,
        experiment,
        run,
        rows,
    })
}

/// Whether `dir` holds a shard of a simulation.
#[must_use]
pub fn is_shard(dir: &Path) -> bool {
    dir.join(SHARD_FILE).is_file()
}

/// Merges the shards in `dirs` (every shard of one simulation, each finished) into `out`:
/// `runs.csv` with the rows of a single run in its order, `summary.md` and the figures
/// (the wall time is the shards' sum, the threads their most).
///
/// # Errors
/// [`SimError::Merge`] naming the folder and the reason (not a shard, another
/// simulation's, a shard missing, twice or not finished); [`SimError::Io`] or
/// [`SimError::Plot`] while writing.
pub fn merge_shards(dirs: &[PathBuf], out: &Path) -> Result<(Summary, Vec<PathBuf>), SimError> {
    let mut shards = Vec::with_capacity(dirs.len());
    for d in dirs {
        shards.push(read_shard(d).map_err(|e| SimError::Merge(format!("{}: {e}", d.display())))?);
    }
    let Some(first) = shards.first() else {
        return Err(SimError::Merge("no shard folder given".into()));
    };
    let count = first.run.shard.count;
    let exp = first.experiment.clone();
    let per = first.rows.len() / first.shard_scenarios.max(1);
    for s in &shards {
        let at = |e: String| SimError::Merge(format!("{}: {e}", s.dir.display()));
        if s.identity != first.identity {
            return Err(at(format!(
                "another simulation's shard than {}'s",
                first.dir.display()
            )));
        }
        if s.run.scenarios_done != s.shard_scenarios {
            return Err(at(format!(
                "shard {}/{count} stopped after {} of its {} scenarios: run it again",
                s.run.shard.index, s.run.scenarios_done, s.shard_scenarios
            )));
        }
        if s.rows.len() != s.shard_scenarios * per || !(1..=count).contains(&s.run.shard.index) {
            return Err(at(format!(
                "runs.csv has {} rows for {} scenarios of {per} estimators",
                s.rows.len(),
                s.shard_scenarios
            )));
        }
    }
    let mut by_index: Vec<Option<&ShardDir>> = vec![None; count];
    for s in &shards {
        let slot = &mut by_index[s.run.shard.index - 1];
        if let Some(other) = slot {
            return Err(SimError::Merge(format!(
                "shard {}/{count} is in both {} and {}",
                s.run.shard.index,
                other.dir.display(),
                s.dir.display()
            )));
        }
        *slot = Some(s);
    }
    let missing: Vec<String> = (1..=count)
        .filter(|i| by_index[i - 1].is_none())
        .map(|i| format!("{i}/{count}"))
        .collect();
    if !missing.is_empty() {
        return Err(SimError::Merge(format!(
            "shard(s) {} missing",
            missing.join(", ")
        )));
    }
    let parts: Vec<&ShardDir> = by_index.into_iter().flatten().collect();
    let total = exp.scenarios();
    let mut rows = Vec::with_capacity(total * per);
    for k in 0..total {
        let (s, j) = (parts[k % count], k / count);
        let chunk = s.rows.get(j * per..(j + 1) * per).ok_or_else(|| {
            SimError::Merge(format!("{}: runs.csv has too few rows", s.dir.display()))
        })?;
        rows.extend_from_slice(chunk);
    }
    let wall = parts.iter().map(|s| s.run.wall).sum();
    let threads = parts.iter().map(|s| s.run.threads).max().unwrap_or(1);
    crate::output::ensure_writable_dir(out)?;
    write_results(&exp, &rows, per, wall, threads, out)
}
