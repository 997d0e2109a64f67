//! `swarmpose.odometry`: a whole sequence directory through the streaming engine, as
//! `swarmpose odometry` runs it.

use std::ops::ControlFlow;
use std::path::PathBuf;

use numpy::{PyArray1, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use swarmpose_odometry::FrameResult;
use swarmpose_runs::config::MAX_FRAME_PERIOD_S;
use swarmpose_runs::output::{Summary, calibration_json};

use crate::arrays::{transforms, vector};
use crate::errors::{NotUsableError, run_error_then};
use crate::evaluate::json_value;
use crate::frame::Frame;
use crate::options::OdometryConfig;
use crate::sequence::{BagArgs, Sequence};

/// Runs the odometry over a whole sequence directory (KITTI, Karlsruhe, EuRoC or TUM
/// RGB-D) or ROS 2 bag (stereo or RGB-D), frame ``i`` at its timestamp (or ``i *
/// frame_period`` seconds without one; RGB-D frames always have one), exactly as
/// ``swarmpose odometry`` does; a bag's ``left``, ``right``, ``depth`` and
/// ``stamp_tolerance`` (milliseconds) as for ``Sequence``; settings as for
/// ``Odometry(...)``: ``config`` (an ``OdometryConfig``) or its keywords. Returns an ``OdometryRun``. The GIL is released
/// during the run; Ctrl-C stops it between frames. A frame that cannot be read stops the
/// run, as on the command line: the exception names the frame and how many were done,
/// and its ``run`` attribute is the ``OdometryRun`` of those frames (so is a
/// ``KeyboardInterrupt``'s). A run that ends with fewer than half of its motions tracked
/// raises ``NotUsableError`` (the command line's exit status 3), its ``run`` the whole run.
#[pyfunction]
#[pyo3(signature = (sequence_dir, *, frame_period = None, left = None, right = None,
                    depth = None, stamp_tolerance = 0.0, config = None, **options))]
#[allow(clippy::too_many_arguments)] // Python's keywords
pub(crate) fn odometry<'py>(
    py: Python<'py>,
    sequence_dir: PathBuf,
    frame_period: Option<f64>,
    left: Option<String>,
    right: Option<String>,
    depth: Option<String>,
    stamp_tolerance: f64,
    config: Option<Bound<'py, OdometryConfig>>,
    options: Option<&Bound<'py, PyDict>>,
) -> PyResult<OdometryRun> {
    let config = OdometryConfig::resolve(py, "odometry", config, options)?;
    let mut run_config = config.get().run_config()?;
    let frame_period = frame_period.unwrap_or(run_config.input.frame_period_s);
    run_config.input.frame_period_s = frame_period;
    if !(frame_period > 0.0 && frame_period <= MAX_FRAME_PERIOD_S) {
        return Err(PyValueError::new_err(format!(
            "frame_period must be a positive number of seconds, at most {MAX_FRAME_PERIOD_S:e}"
        )));
    }
    let seq = Sequence::open(
        &sequence_dir,
        BagArgs {
            left,
            right,
            depth,
            stamp_tolerance,
        },
    )?;
    let mut engine = seq.engine(config.get())?;
    let mut frames: Vec<FrameResult> = Vec::with_capacity(seq.inner.len());
    let mut interrupted: Option<PyErr> = None;
    let ended = py.detach(|| {
        seq.run(&mut engine, frame_period, &mut |r| {
            frames.push(r.clone());
            match Python::attach(|py| py.check_signals()) {
                Ok(()) => ControlFlow::Continue(()),
                Err(e) => {
                    interrupted = Some(e);
                    ControlFlow::Break(())
                }
            }
        })
    });
    let error = match (interrupted, ended) {
        (Some(e), _) => Some(e),
        (None, Err(e)) => Some(run_error_then(
            &e,
            &format!(
                "; stopped after {} frame(s): the exception's `run` holds them",
                frames.len()
            ),
        )),
        (None, Ok(_)) => not_usable(&frames),
    };
    let calibration = json_value(py, &calibration_json(&engine.calibration()))?.unbind();
    let run = OdometryRun {
        config_json: run_config
            .to_json()
            .map_err(|e| PyValueError::new_err(e.to_string()))?,
        frames,
        ground_truth: seq.inner.ground_truth().map(<[_]>::to_vec),
        calibration,
    };
    match error {
        None => Ok(run),
        Some(e) => {
            // The frames done are kept (the command line keeps their poses on disk).
            e.value(py).setattr("run", Py::new(py, run)?)?;
            Err(e)
        }
    }
}

/// [`NotUsableError`] for a run whose frames are mostly not tracked (the command line's
/// exit status 3), as [`swarmpose_runs::output::Summary::not_usable`] says.
fn not_usable(frames: &[FrameResult]) -> Option<PyErr> {
    let mut summary = Summary::default();
    frames.iter().for_each(|r| summary.add(r));
    summary.not_usable().map(|why| {
        NotUsableError::new_err(format!("{why}; the exception's `run` holds every frame"))
    })
}

/// The result of ``swarmpose.odometry``: every frame, and the sequence's ground truth.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct OdometryRun {
    /// The run's configuration, as a configuration file holds it.
    config_json: String,
    frames: Vec<FrameResult>,
    ground_truth: Option<Vec<nalgebra::Isometry3<f64>>>,
    calibration: Py<PyAny>,
}

#[pymethods]
impl OdometryRun {
    /// The run's configuration as the text of a configuration file (what the command
    /// line writes as ``config.json``): saved to a file and given as
    /// ``config_file=``, it reruns this run exactly.
    #[getter]
    fn config_json(&self) -> &str {
        &self.config_json
    }

    /// Poses of the left camera in the first frame's, (N, 4, 4) (metres).
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let p: Vec<_> = self.frames.iter().map(|f| f.pose).collect();
        transforms(py, &p)
    }

    /// Each frame's last estimate by the sliding window (a fixed-lag smoother: the pose it
    /// had when it left the window), (N, 4, 4) (metres); ``poses`` without the window.
    #[getter]
    fn smoothed_poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let mut s = swarmpose_runs::output::Smoothed::default();
        for f in &self.frames {
            s.add(f);
        }
        transforms(py, s.poses())
    }

    /// Timestamps, seconds, (N,).
    #[getter]
    fn timestamps<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let t: Vec<f64> = self.frames.iter().map(|f| f.timestamp_s).collect();
        vector(py, &t)
    }

    /// The status of each frame (see ``Frame.status``).
    #[getter]
    fn statuses(&self) -> Vec<String> {
        self.frames.iter().map(|f| f.status.text()).collect()
    }

    /// Every frame's ``Frame``.
    #[getter]
    fn frames(&self) -> Vec<Frame> {
        self.frames
            .iter()
            .map(|r| Frame { result: r.clone() })
            .collect()
    }

    /// The sequence's ground-truth poses, (N, 4, 4), or ``None``.
    #[getter]
    fn ground_truth<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f64>>> {
        self.ground_truth.as_deref().map(|g| transforms(py, g))
    }

    /// The self-calibration's decision at the end of the run.
    #[getter]
    fn calibration(&self, py: Python<'_>) -> Py<PyAny> {
        self.calibration.clone_ref(py)
    }

    fn __len__(&self) -> usize {
        self.frames.len()
    }

    fn __repr__(&self) -> String {
        let tracked = self.frames.iter().filter(|f| f.status.is_tracked()).count();
        format!(
            "OdometryRun(frames={}, tracked={tracked})",
            self.frames.len()
        )
    }
}
