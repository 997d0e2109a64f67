//! `swarmpose.batch`'s native half: the items of a batch manifest run by the command
//! line's own code ([`swarmpose_cli::batch`]), so that a batch run from Python (in a
//! process pool or on Ray) writes the same folders and summaries as `swarmpose batch`.

use std::path::PathBuf;

use pyo3::exceptions::{PyOSError, PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use swarmpose_cli::batch::item::{Outcome, run_item};
use swarmpose_cli::batch::manifest::{Manifest, Shard};
use swarmpose_cli::batch::merge::MergeArgs;
use swarmpose_cli::error::{CliError, EXIT_USAGE};

/// A command-line error as a Python exception: `ValueError` for bad input (exit status
/// 2), `OSError` for the rest.
fn py_err(e: &CliError) -> PyErr {
    if e.code == EXIT_USAGE {
        PyValueError::new_err(e.message.clone())
    } else {
        PyOSError::new_err(e.message.clone())
    }
}

/// Checks the manifest (every item's options too), creates ``out`` and writes its
/// ``batch.json``; returns the names of the items of shard ``index``/``count``, in the
/// manifest's order.
#[pyfunction]
#[pyo3(name = "_batch_prepare", signature = (manifest, out, index = 1, count = 1))]
pub(crate) fn batch_prepare(
    manifest: PathBuf,
    out: PathBuf,
    index: usize,
    count: usize,
) -> PyResult<Vec<String>> {
    let shard: Shard = format!("{index}/{count}")
        .parse()
        .map_err(PyValueError::new_err)?;
    let m = swarmpose_cli::batch::prepare(&manifest, &out).map_err(|e| py_err(&e))?;
    Ok(m.shard(shard).iter().map(|i| i.name.clone()).collect())
}

/// Runs item ``name`` of ``manifest`` into ``out/name`` as ``swarmpose batch`` does
/// (skipped when its summary says it is done); returns ``(summary.json's text,
/// skipped)``. The GIL is released while it runs.
#[pyfunction]
#[pyo3(name = "_batch_item")]
pub(crate) fn batch_item(
    py: Python<'_>,
    manifest: PathBuf,
    out: PathBuf,
    name: String,
) -> PyResult<(String, bool)> {
    let m = Manifest::load(&manifest).map_err(|e| py_err(&e))?;
    let Some(item) = m.items.iter().find(|i| i.name == name) else {
        return Err(PyValueError::new_err(format!(
            "{}: no item named {name}",
            manifest.display()
        )));
    };
    let outcome = py.detach(|| run_item(item, &out)).map_err(|e| py_err(&e))?;
    let (summary, skipped) = match outcome {
        Outcome::Ran(s) => (s, false),
        Outcome::Skipped(s) => (s, true),
        Outcome::Busy(why) => return Err(PyRuntimeError::new_err(why)),
    };
    let text = serde_json::to_string(&summary)
        .map_err(|e| PyRuntimeError::new_err(format!("summary.json: {e}")))?;
    Ok((text, skipped))
}

/// ``swarmpose batch merge DIRS --out OUT``: writes ``batch.csv`` and ``batch.md``;
/// returns its exit status (0: every item succeeded, 3: some did not or are missing)
/// and message.
#[pyfunction]
#[pyo3(name = "_batch_merge", signature = (dirs, out = None))]
pub(crate) fn batch_merge(
    py: Python<'_>,
    dirs: Vec<PathBuf>,
    out: Option<PathBuf>,
) -> PyResult<(u8, String)> {
    let args = MergeArgs { dirs, out };
    let (result, _console) =
        py.detach(|| swarmpose_cli::streams::capture(|| swarmpose_cli::batch::merge::run(&args)));
    match result {
        Ok(()) => Ok((0, String::new())),
        Err(e) if e.code == swarmpose_cli::error::EXIT_NOT_USABLE => Ok((e.code, e.message)),
        Err(e) => Err(py_err(&e)),
    }
}
