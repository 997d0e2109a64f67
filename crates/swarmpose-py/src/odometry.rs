//! `swarmpose.Odometry` (the streaming engine: frames in, poses out) and
//! `swarmpose.odometry` (a whole sequence directory through the same engine).

use std::ops::ControlFlow;
use std::path::PathBuf;

use numpy::{PyArray1, PyArray3};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use swarmpose_odometry::batch::{camera_of, run_sequence};
use swarmpose_odometry::config::Calibration;
use swarmpose_odometry::output::calibration_json;
use swarmpose_odometry::{CorrectionModel, FrameResult, OdometryConfig, StereoCamera, StereoInput};
use swarmpose_vision::features::GrayView;
use swarmpose_vision::frontend::{Detector, DisparityCorrection};
use swarmpose_vision::stereo::RectifiedStereo;

use crate::arrays::{GrayArray, transforms, vector};
use crate::errors::odometry_error;
use crate::evaluate::json_value;
use crate::frame::Frame;
use crate::methods;
use crate::sequence::{Sequence, camera_dict};

/// The engine's settings as keyword arguments (defaults: those of
/// [`OdometryConfig::default`] and of the command line).
struct Options<'a> {
    method: &'a str,
    threshold: Option<f64>,
    detector: &'a str,
    refine: bool,
    calibrate: Option<&'a str>,
    disparity_correction: Option<(f64, f64)>,
    min_inliers: Option<usize>,
    seed: u64,
}

impl Options<'_> {
    fn config(&self) -> PyResult<OdometryConfig> {
        let detector: Detector =
            self.detector
                .parse()
                .map_err(|e: swarmpose_vision::frontend::UnknownDetector| {
                    PyValueError::new_err(e.to_string())
                })?;
        let mut c = OdometryConfig {
            detector,
            refine: self.refine,
            seed: self.seed,
            ..OdometryConfig::default()
        };
        if let Some(n) = self.min_inliers {
            if n < 3 {
                return Err(PyValueError::new_err(format!(
                    "min_inliers {n}: at least 3 are needed for a motion"
                )));
            }
            c.min_inliers = n;
        }
        if let Some(causes) = self.calibrate {
            let model = CorrectionModel::parse(causes).map_err(PyValueError::new_err)?;
            c.selfcal.candidates = model;
            if model == CorrectionModel::NONE {
                c.calibration = Calibration::Off;
            }
        }
        if let Some((offset_px, quadratic_px)) = self.disparity_correction {
            if !(offset_px.is_finite() && quadratic_px.is_finite()) {
                return Err(PyValueError::new_err(
                    "disparity_correction (offset, quadratic) must be finite numbers of pixels",
                ));
            }
            c.calibration = Calibration::Fixed(DisparityCorrection {
                offset_px,
                quadratic_px,
                ..DisparityCorrection::default()
            });
        }
        Ok(c)
    }

    fn build(&self, camera: StereoCamera) -> PyResult<swarmpose_odometry::Odometry> {
        let config = self.config()?;
        let estimator = methods::estimator(self.method, self.threshold)?;
        swarmpose_odometry::Odometry::builder(camera)
            .config(config)
            .estimator(estimator)
            .build()
            .map_err(|e| odometry_error(&e))
    }
}

/// A streaming stereo visual odometry: ``track`` takes one rectified stereo pair at a
/// time and returns its pose at once (a ``Frame``). Its memory does not grow with the
/// number of frames.
#[pyclass(module = "swarmpose")]
pub(crate) struct Odometry {
    inner: swarmpose_odometry::Odometry,
}

#[pymethods]
impl Odometry {
    /// An engine for a rectified stereo camera: focal lengths ``fx``, ``fy`` and
    /// principal point ``cx``, ``cy`` in pixels, ``baseline`` in metres, images of
    /// ``width`` x ``height`` pixels. Options: ``method`` (one of ``swarmpose.METHODS``)
    /// and its ``threshold`` (metres), ``detector`` (``"orb"`` or ``"surf"``),
    /// ``refine`` (reprojection refinement), ``calibrate`` (the causes self-calibration
    /// may correct, e.g. ``"principal-point+yaw"``, or ``"none"``; default as the
    /// command line), ``disparity_correction`` (a fixed ``(offset, quadratic)`` in
    /// pixels instead), ``min_inliers``, ``seed`` (frame k uses seed + k).
    #[new]
    #[pyo3(signature = (fx, fy, cx, cy, baseline, width, height, *, method = "pso", threshold = None,
        detector = "orb", refine = true, calibrate = None, disparity_correction = None,
        min_inliers = None, seed = 0))]
    #[allow(clippy::too_many_arguments)]
    fn new(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        baseline: f64,
        width: usize,
        height: usize,
        method: &str,
        threshold: Option<f64>,
        detector: &str,
        refine: bool,
        calibrate: Option<&str>,
        disparity_correction: Option<(f64, f64)>,
        min_inliers: Option<usize>,
        seed: u64,
    ) -> PyResult<Self> {
        let camera = StereoCamera {
            rig: RectifiedStereo {
                fx,
                fy,
                cx,
                cy,
                baseline_m: baseline,
            },
            width,
            height,
        };
        let options = Options {
            method,
            threshold,
            detector,
            refine,
            calibrate,
            disparity_correction,
            min_inliers,
            seed,
        };
        Ok(Self {
            inner: options.build(camera)?,
        })
    }

    /// An engine for the camera of a sequence directory (its calibration and image
    /// size); options as for ``Odometry(...)``.
    #[staticmethod]
    #[pyo3(signature = (sequence_dir, *, method = "pso", threshold = None, detector = "orb",
        refine = true, calibrate = None, disparity_correction = None, min_inliers = None, seed = 0))]
    #[allow(clippy::too_many_arguments)]
    fn from_sequence(
        sequence_dir: PathBuf,
        method: &str,
        threshold: Option<f64>,
        detector: &str,
        refine: bool,
        calibrate: Option<&str>,
        disparity_correction: Option<(f64, f64)>,
        min_inliers: Option<usize>,
        seed: u64,
    ) -> PyResult<Self> {
        let seq = Sequence::open(&sequence_dir)?;
        let options = Options {
            method,
            threshold,
            detector,
            refine,
            calibrate,
            disparity_correction,
            min_inliers,
            seed,
        };
        Ok(Self {
            inner: options.build(camera_of(seq.inner.as_ref()))?,
        })
    }

    /// Takes the next stereo pair (rectified, (height, width) uint8 arrays of the
    /// camera's size) taken at ``timestamp`` seconds (strictly increasing) and returns
    /// its ``Frame``. The GIL is released while it works. Raises ``ValueError`` for
    /// images that do not fit the camera or a timestamp that does not increase; the
    /// engine is then unchanged and the next frame can be given.
    fn track(
        &mut self,
        py: Python<'_>,
        left: &Bound<'_, PyAny>,
        right: &Bound<'_, PyAny>,
        timestamp: f64,
    ) -> PyResult<Frame> {
        let l = GrayArray::new("left", left)?;
        let r = GrayArray::new("right", right)?;
        let ((lw, lh), (rw, rh)) = (l.size(), r.size());
        let (lp, rp) = (l.pixels(), r.pixels());
        let input = StereoInput {
            left: GrayView {
                width: lw,
                height: lh,
                data: &lp,
            },
            right: GrayView {
                width: rw,
                height: rh,
                data: &rp,
            },
            timestamp_s: timestamp,
        };
        let engine = &mut self.inner;
        let result = py
            .detach(move || engine.track(input))
            .map_err(|e| odometry_error(&e))?;
        Ok(Frame { result })
    }

    /// The camera: fx, fy, cx, cy (pixels), baseline (metres), width, height.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera_dict(py, self.inner.camera())
    }

    /// The detector's name.
    #[getter]
    fn detector(&self) -> &'static str {
        self.inner.detector()
    }

    /// The estimator's name.
    #[getter]
    fn method(&self) -> &'static str {
        self.inner.estimator()
    }

    /// The self-calibration's current decision and its evidence (as the CLI's
    /// ``calibration.json``).
    #[getter]
    fn calibration<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_value(py, &calibration_json(self.inner.calibration()))
    }

    /// Heap bytes of the engine's per-frame state (it does not grow with the frames).
    #[getter]
    fn state_bytes(&self) -> usize {
        self.inner.state_bytes()
    }

    fn __repr__(&self) -> String {
        format!(
            "Odometry(detector={:?}, method={:?})",
            self.inner.detector(),
            self.inner.estimator()
        )
    }
}

/// Runs the odometry over a whole stereo sequence directory (KITTI, Karlsruhe or
/// EuRoC), frame ``i`` at ``i * frame_period`` seconds, exactly as ``swarmpose
/// odometry`` does; options as for ``Odometry(...)``. Returns an ``OdometryRun``.
/// The GIL is released during the run; Ctrl-C stops it between frames.
#[pyfunction]
#[pyo3(signature = (sequence_dir, *, frame_period = 0.1, method = "pso", threshold = None,
    detector = "orb", refine = true, calibrate = None, disparity_correction = None,
    min_inliers = None, seed = 0))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn odometry(
    py: Python<'_>,
    sequence_dir: PathBuf,
    frame_period: f64,
    method: &str,
    threshold: Option<f64>,
    detector: &str,
    refine: bool,
    calibrate: Option<&str>,
    disparity_correction: Option<(f64, f64)>,
    min_inliers: Option<usize>,
    seed: u64,
) -> PyResult<OdometryRun> {
    if !(frame_period.is_finite() && frame_period > 0.0) {
        return Err(PyValueError::new_err(
            "frame_period must be a positive number of seconds",
        ));
    }
    let seq = Sequence::open(&sequence_dir)?;
    let options = Options {
        method,
        threshold,
        detector,
        refine,
        calibrate,
        disparity_correction,
        min_inliers,
        seed,
    };
    let mut engine = options.build(camera_of(seq.inner.as_ref()))?;
    let mut frames: Vec<FrameResult> = Vec::with_capacity(seq.inner.len());
    let mut interrupted: Option<PyErr> = None;
    let ended = py.detach(|| {
        run_sequence(seq.inner.as_ref(), &mut engine, frame_period, &mut |r| {
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
    if let Some(e) = interrupted {
        return Err(e);
    }
    ended.map_err(|e| odometry_error(&e))?;
    let calibration = json_value(py, &calibration_json(engine.calibration()))?.unbind();
    Ok(OdometryRun {
        frames,
        ground_truth: seq.inner.ground_truth().map(<[_]>::to_vec),
        calibration,
    })
}

/// The result of ``swarmpose.odometry``: every frame, and the sequence's ground truth.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct OdometryRun {
    frames: Vec<FrameResult>,
    ground_truth: Option<Vec<nalgebra::Isometry3<f64>>>,
    calibration: Py<PyAny>,
}

#[pymethods]
impl OdometryRun {
    /// Poses of the left camera in the first frame's, (N, 4, 4) (metres).
    #[getter]
    fn poses<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray3<f64>> {
        let p: Vec<_> = self.frames.iter().map(|f| f.pose).collect();
        transforms(py, &p)
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
