//! `swarmpose.evaluate`: the metrics of an estimated trajectory against the ground
//! truth, as `swarmpose evaluate --json` prints them (its `"kitti"` entry as
//! `--kitti-segments --json`).

use std::path::PathBuf;

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use swarmpose_eval::associate::{DEFAULT_MAX_DIFF_S, by_index, by_timestamp};
use swarmpose_eval::{Format, Trajectory, evaluate_with};

use crate::arrays::poses;
use crate::errors::eval_error;

/// A JSON value as Python objects (through the `json` module).
pub(crate) fn json_value<'py>(
    py: Python<'py>,
    v: &serde_json::Value,
) -> PyResult<Bound<'py, PyAny>> {
    py.import("json")?.call_method1("loads", (v.to_string(),))
}

/// A trajectory argument: an (N, 4, 4) array, or a path to a file in `format`.
fn trajectory(
    name: &str,
    obj: &Bound<'_, PyAny>,
    format: Option<Format>,
) -> PyResult<(Trajectory, Option<Format>)> {
    if let Ok(path) = obj.extract::<PathBuf>() {
        let f = format.unwrap_or_else(|| Format::guess(&path));
        return Trajectory::read(&path, f)
            .map(|t| (t, Some(f)))
            .map_err(|e| eval_error(&e));
    }
    Ok((Trajectory::indexed(name, poses(name, obj)?), None))
}

/// The trajectory metrics of ``estimate`` against ``ground_truth`` as a dict (the
/// fields of ``swarmpose evaluate --json``: eq. (20) per frame and its RMS, ATE raw
/// and SE(3)-aligned, RPE, final drift, KITTI segment errors).
///
/// Each argument is an (N, 4, 4) array of camera-to-world poses (paired by index) or
/// a path to a trajectory file; ``format`` is ``"kitti"`` (paired by line) or
/// ``"tum"`` (paired by timestamp within ``max_diff`` seconds), guessed from the file
/// name when ``None``.
///
/// ``result["kitti"]`` holds the KITTI devkit's segment errors, as ``swarmpose evaluate
/// --kitti-segments --json`` prints them: for segments of 100, 200, ..., 800 m of
/// ground-truth path starting every 10 frames, the translation error in percent and the
/// rotation error in degrees per 100 m, per length (``per_length``), over all segments
/// (``translation_percent``, ``rotation_deg_per_100m``; ``None`` without a segment) and
/// per segment (``segments``). ``segment_scale`` in (0, 1] multiplies the lengths, for
/// clips shorter than 100 m; its ``note`` then says they are not the KITTI benchmark's
/// figures.
///
/// Raises ``ValueError`` for malformed or mismatched input or a bad ``segment_scale``,
/// ``FileNotFoundError``/``OSError`` for paths.
#[pyfunction]
#[pyo3(signature = (estimate, ground_truth, *, format = None, max_diff = DEFAULT_MAX_DIFF_S, segment_scale = 1.0))]
pub(crate) fn evaluate<'py>(
    py: Python<'py>,
    estimate: &Bound<'py, PyAny>,
    ground_truth: &Bound<'py, PyAny>,
    format: Option<&str>,
    max_diff: f64,
    segment_scale: f64,
) -> PyResult<Bound<'py, PyAny>> {
    let format = match format {
        None => None,
        Some("kitti") => Some(Format::Kitti),
        Some("tum") => Some(Format::Tum),
        Some(other) => {
            return Err(PyValueError::new_err(format!(
                "format {other:?}: \"kitti\" or \"tum\" expected"
            )));
        }
    };
    if !(max_diff.is_finite() && max_diff >= 0.0) {
        return Err(PyValueError::new_err(
            "max_diff must be a finite number of seconds >= 0",
        ));
    }
    let (est, est_format) = trajectory("estimate", estimate, format)?;
    let (gt, gt_format) = trajectory("ground_truth", ground_truth, format)?;
    let pairs = match est_format.or(gt_format) {
        Some(Format::Tum) => by_timestamp(&est, &gt, max_diff),
        Some(Format::Kitti) | None => by_index(&est, &gt),
    }
    .map_err(|e| eval_error(&e))?;
    let metrics = py
        .detach(|| evaluate_with(&pairs, segment_scale))
        .map_err(|e| eval_error(&e))?;
    let value = serde_json::to_value(&metrics)
        .map_err(|e| PyTypeError::new_err(format!("cannot encode the metrics: {e}")))?;
    json_value(py, &value)
}
