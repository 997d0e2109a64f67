//! The files of a whole simulation from its rows: `runs.csv`, `summary.md` and the
//! figures (for [`crate::simulate()`] and for merged shards, [`crate::shard`]).

use std::path::{Path, PathBuf};
use std::time::Duration;

use crate::error::SimError;
use crate::experiment::Experiment;
use crate::metrics::RunRecord;
use crate::output::write_file;
use crate::plots::write_figures;
use crate::report::summary_markdown;
use crate::runs_csv::runs_csv;
use crate::stats::Summary;

/// Writes `runs.csv`, and `summary.md` with the figures when every scenario of `exp` has
/// its `per_scenario` rows (else a `summary.md` that says where the run stopped), into
/// `dir`; returns the summary and the files written.
///
/// # Errors
/// [`SimError::Io`] or [`SimError::Plot`].
pub fn write_results(
    exp: &Experiment,
    rows: &[RunRecord],
    per_scenario: usize,
    wall: Duration,
    threads: usize,
    dir: &Path,
) -> Result<(Summary, Vec<PathBuf>), SimError> {
    let summary = Summary::new(exp, rows);
    let scenarios_done = rows.len() / per_scenario.max(1);
    let mut files = Vec::new();
    let csv = dir.join("runs.csv");
    let text = runs_csv(rows).map_err(|e| SimError::io(&csv, e.into()))?;
    write_file(&csv, text)?;
    files.push(csv);
    let md = dir.join("summary.md");
    if scenarios_done < exp.scenarios() {
        let note = format!(
            "# Stopped\n\nThe simulation was stopped after {scenarios_done} of {} scenarios \
             ({:.1} s): runs.csv holds their rows; no tables or figures were made.\n",
            exp.scenarios(),
            wall.as_secs_f64()
        );
        write_file(&md, note)?;
        files.push(md);
    } else {
        write_file(
            &md,
            summary_markdown(exp, &summary, wall.as_secs_f64(), threads),
        )?;
        files.push(md);
        files.extend(write_figures(&summary, dir)?);
    }
    Ok((summary, files))
}
