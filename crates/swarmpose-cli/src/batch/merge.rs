//! `swarmpose batch merge DIR... [--out DIR]`: the summaries of every item of one or
//! more batch output folders as one table, `batch.csv` and `batch.md`
//! ([`super::table`]); or, for folders of `swarmpose simulate --shard`, one simulation.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

use clap::Args;

use super::ITEMS;
use super::item::{STATUS_OK, read_summary};
use super::table::{Row, aggregates, csv, markdown};
use crate::error::{CliError, EXIT_NOT_USABLE};
use crate::output_file::write_bytes;
use crate::streams::out;

/// Arguments of `swarmpose batch merge`.
#[derive(Debug, Args)]
#[command(after_help = "\
Reads DIR/<item>/summary.json of every item in each DIR (and DIR/batch.json, the list of the \
manifest's items, so that an item not run yet is listed as missing) and writes batch.csv and \
batch.md into --out (default: the first DIR): one row per item, sorted by name, numbers at \
fixed precision and no times, so that the table is the same bytes however the batch was \
sharded; batch.md ends with the counts by status and the mean figures over the items that \
succeeded. An item found in two folders is an error. Folders of `swarmpose simulate --shard \
i/N` are merged into one simulation in --out (runs.csv, summary.md, figures).

Exit status: 0 when every item succeeded; 3 when the table is written but some item did not \
succeed or is missing; 2 for a folder that is not a batch's; 1 when the table cannot be \
written.")]
pub struct MergeArgs {
    /// Batch output folders (the shards of one batch), or `simulate --shard` folders.
    #[arg(value_name = "DIR", required = true, num_args = 1..)]
    pub dirs: Vec<PathBuf>,

    /// Where the merged table goes (default: the first DIR).
    #[arg(long, value_name = "DIR")]
    pub out: Option<PathBuf>,
}

/// The summaries under `dir` and the manifest's item names.
fn read_dir(dir: &Path) -> Result<(Vec<Row>, Vec<String>), CliError> {
    let bad = |e: &dyn std::fmt::Display| CliError::usage(format!("{}: {e}", dir.display()));
    let mut expected = Vec::new();
    match std::fs::read_to_string(dir.join(ITEMS)) {
        Ok(text) => {
            let v: serde_json::Value = serde_json::from_str(&text).map_err(|e| bad(&e))?;
            let names = v.get("items").and_then(|i| i.as_array());
            for n in names.into_iter().flatten() {
                expected.extend(n.as_str().map(str::to_owned));
            }
        }
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => return Err(bad(&e)),
    }
    let mut rows = Vec::new();
    for entry in std::fs::read_dir(dir).map_err(|e| bad(&e))? {
        let entry = entry.map_err(|e| bad(&e))?;
        if entry.path().is_dir()
            && let Some(s) = read_summary(&entry.path())
        {
            rows.push(Row::Done(Box::new(s)));
        }
    }
    if rows.is_empty() && expected.is_empty() {
        return Err(bad(&format!(
            "no {ITEMS} and no item's summary.json: not a batch output folder"
        )));
    }
    Ok((rows, expected))
}

/// Every row of `dirs`, sorted by name (the manifest's items without a summary as
/// missing).
///
/// # Errors
/// A folder that is not a batch's (exit status 2), an item in two folders.
pub fn collect(dirs: &[PathBuf]) -> Result<Vec<Row>, CliError> {
    let mut seen: Vec<PathBuf> = Vec::new();
    let mut rows: BTreeMap<String, (Row, PathBuf)> = BTreeMap::new();
    let mut expected: Vec<String> = Vec::new();
    for dir in dirs {
        let real = std::fs::canonicalize(dir)
            .map_err(|e| CliError::usage(format!("{}: {e}", dir.display())))?;
        if seen.contains(&real) {
            continue;
        }
        seen.push(real);
        let (found, names) = read_dir(dir)?;
        expected.extend(names);
        for row in found {
            let name = row.name().to_owned();
            if let Some((_, other)) = rows.get(&name) {
                return Err(CliError::usage(format!(
                    "item {name} is in both {} and {}: merge the folders of one batch",
                    other.display(),
                    dir.display()
                )));
            }
            rows.insert(name, (row, dir.clone()));
        }
    }
    for name in expected {
        rows.entry(name.clone())
            .or_insert_with(|| (Row::Missing(name), PathBuf::new()));
    }
    Ok(rows.into_values().map(|(r, _)| r).collect())
}

/// Runs `batch merge`.
///
/// # Errors
/// See the command's help.
pub fn run(args: &MergeArgs) -> Result<(), CliError> {
    if crate::commands::simulate_shard::is_shard(&args.dirs) {
        return crate::commands::simulate_shard::merge(&args.dirs, args.out.as_deref());
    }
    let rows = collect(&args.dirs)?;
    let to = args.out.clone().unwrap_or_else(|| args.dirs[0].clone());
    let table_path = to.join("batch.csv");
    let table = csv(&rows)
        .map_err(|e| CliError::failure(format!("cannot write {}: {e}", table_path.display())))?;
    write_bytes(&table_path, &table)?;
    write_bytes(&to.join("batch.md"), markdown(&rows).as_bytes())?;
    for line in aggregates(&rows) {
        out(&line)?;
    }
    out(&format!(
        "wrote {} and {}",
        to.join("batch.csv").display(),
        to.join("batch.md").display()
    ))?;
    let bad: Vec<&str> = rows
        .iter()
        .filter(|r| r.status() != STATUS_OK)
        .map(Row::name)
        .collect();
    if bad.is_empty() {
        Ok(())
    } else {
        Err(CliError {
            code: EXIT_NOT_USABLE,
            message: format!(
                "{} of {} item(s) did not succeed or are missing ({}); the table is written",
                bad.len(),
                rows.len(),
                bad.join(", ")
            ),
        })
    }
}
