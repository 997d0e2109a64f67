//! `swarmpose simulate --shard i/N` folders merged by `swarmpose batch merge` into one
//! simulation ([`swarmpose_sim::shard`]).

use std::path::{Path, PathBuf};

use swarmpose_sim::SimError;
use swarmpose_sim::report::console_summary;
use swarmpose_sim::shard::merge_shards;

use crate::error::CliError;
use crate::streams::out_text;

/// Whether `dirs` are shards of a simulation (the first one is).
#[must_use]
pub fn is_shard(dirs: &[PathBuf]) -> bool {
    dirs.first()
        .is_some_and(|d| swarmpose_sim::shard::is_shard(d))
}

/// Merges the shards in `dirs` into `out`.
///
/// # Errors
/// Exit status 2 when the folders do not make one whole simulation, or `out` is not
/// given; 1 when the results cannot be written.
pub fn merge(dirs: &[PathBuf], out: Option<&Path>) -> Result<(), CliError> {
    let Some(out) = out else {
        return Err(CliError::usage(
            "merging simulate shards needs --out DIR (the merged simulation's folder)",
        ));
    };
    let (summary, files) = merge_shards(dirs, out).map_err(|e| match e {
        SimError::Merge(_) => CliError::usage(e.to_string()),
        other => CliError::failure(other.to_string()),
    })?;
    let mut text = console_summary(&summary);
    for f in &files {
        text.push_str(&format!("wrote {}\n", f.display()));
    }
    out_text(&text)
}
