//! `swarmpose.Odometry`: the streaming engine, frames in, poses out (stereo pairs, or
//! RGB-D frames for an engine made by `Odometry.rgbd`).

use std::path::PathBuf;
use std::sync::{Mutex, MutexGuard};

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::{FrameResult, OdometryError, RgbdInput, StereoCamera, StereoInput};
use swarmpose_runs::output::calibration_json;
use swarmpose_vision::stereo::RectifiedStereo;

use crate::arrays::ImageArray;
use crate::errors::odometry_error;
use crate::evaluate::json_value;
use crate::frame::Frame;
use crate::options::OdometryConfig;
use crate::sequence::{BagArgs, Sequence, camera_dict};

/// A streaming stereo visual odometry: ``track`` takes one rectified stereo pair at a
/// time and returns its pose at once (a ``Frame``). Its memory does not grow with the
/// number of frames. Threads may share one: its frames are taken one at a time, in the
/// order the threads reach it.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct Odometry {
    /// One frame at a time: a second thread's frame waits for the first (with the GIL
    /// released), where pyo3's borrow check raised "Already borrowed".
    inner: Mutex<swarmpose_odometry::Odometry>,
}

/// The camera of a constructor's arguments: focal lengths and principal point, pixels;
/// the baseline, metres; the image size (width, height), pixels.
fn camera(
    fx: f64,
    fy: f64,
    cx: f64,
    cy: f64,
    baseline_m: f64,
    size: (usize, usize),
) -> StereoCamera {
    StereoCamera {
        rig: RectifiedStereo {
            fx,
            fy,
            cx,
            cy,
            baseline_m,
        },
        width: size.0,
        height: size.1,
    }
}

impl Odometry {
    fn of(engine: swarmpose_odometry::Odometry) -> Self {
        Self {
            inner: Mutex::new(engine),
        }
    }

    /// The engine, waited for while another thread's frame is in it.
    fn engine(&self) -> PyResult<MutexGuard<'_, swarmpose_odometry::Odometry>> {
        self.inner.lock().map_err(|_| {
            PyRuntimeError::new_err(
                "this Odometry stopped in the middle of a frame (a panic): make a new one",
            )
        })
    }

    /// The `Frame` of one frame given to the engine by `track` (`track` or `track_rgbd`),
    /// with the GIL released while it works.
    fn run<F>(&self, py: Python<'_>, track: F) -> PyResult<Frame>
    where
        F: FnOnce(&mut swarmpose_odometry::Odometry) -> Result<FrameResult, OdometryError> + Send,
    {
        let result = py.detach(move || {
            let mut engine = self.engine()?;
            track(&mut engine).map_err(|e| odometry_error(&e))
        })?;
        Ok(Frame { result })
    }
}

#[pymethods]
impl Odometry {
    /// An engine for a rectified stereo camera: focal lengths ``fx``, ``fy`` and
    /// principal point ``cx``, ``cy`` in pixels, ``baseline`` in metres, images of
    /// ``width`` x ``height`` pixels. Its settings: ``config`` (an ``OdometryConfig``),
    /// or ``OdometryConfig``'s keywords themselves (``method``, ``window``, ...), not
    /// both; the defaults are the command line's.
    #[new]
    #[pyo3(signature = (fx, fy, cx, cy, baseline, width, height, *, config = None, **options))]
    #[allow(clippy::too_many_arguments)]
    fn new<'py>(
        py: Python<'py>,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        baseline: f64,
        width: usize,
        height: usize,
        config: Option<Bound<'py, OdometryConfig>>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Self> {
        let config = OdometryConfig::resolve(py, "Odometry", config, options)?;
        let camera = camera(fx, fy, cx, cy, baseline, (width, height));
        Ok(Self::of(config.get().build(camera, None)?))
    }

    /// An engine for the camera of a sequence directory or bag (its calibration and image
    /// size; an RGB-D input's engine takes ``track_rgbd`` frames, as from
    /// ``Odometry.rgbd``); settings as for ``Odometry(...)``: ``config`` or
    /// ``OdometryConfig``'s keywords.
    #[staticmethod]
    #[pyo3(signature = (sequence_dir, *, config = None, **options))]
    fn from_sequence<'py>(
        py: Python<'py>,
        sequence_dir: PathBuf,
        config: Option<Bound<'py, OdometryConfig>>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Self> {
        let config = OdometryConfig::resolve(py, "Odometry.from_sequence", config, options)?;
        let seq = Sequence::open(&sequence_dir, BagArgs::default())?;
        Ok(Self::of(seq.engine(config.get())?))
    }

    /// Takes the next stereo pair (rectified, (height, width) uint8 arrays of the
    /// camera's size) taken at ``timestamp`` seconds (strictly increasing) and returns
    /// its ``Frame``. The GIL is released while it works. Raises ``ValueError`` for
    /// images that do not fit the camera or a timestamp that does not increase; the
    /// engine is then unchanged and the next frame can be given.
    fn track(
        &self,
        py: Python<'_>,
        left: &Bound<'_, PyAny>,
        right: &Bound<'_, PyAny>,
        timestamp: f64,
    ) -> PyResult<Frame> {
        let l = ImageArray::<u8>::new("left", left, "uint8")?;
        let r = ImageArray::<u8>::new("right", right, "uint8")?;
        let (lp, rp) = (l.pixels(), r.pixels());
        let input = StereoInput {
            left: lp.gray(),
            right: rp.gray(),
            timestamp_s: timestamp,
        };
        self.run(py, move |engine| engine.track(input))
    }

    /// An engine for an RGB-D camera (focal lengths and principal point in pixels,
    /// images of ``width`` x ``height``): frames go to ``track_rgbd``. Depth noise
    /// ``sigma_z = depth_coefficient * z**2`` (1/m; the Kinect v1's by default). Settings
    /// as for ``Odometry(...)`` (``config`` or ``OdometryConfig``'s keywords), but ORB
    /// features only, and ``ValueError`` for the ones only a stereo camera has a use for
    /// (``calibrate``, ``disparity_correction``, ``max_working_pixels``,
    /// ``min_working_pixels``).
    #[staticmethod]
    #[pyo3(signature = (fx, fy, cx, cy, width, height, *, depth_coefficient = None,
        config = None, **options))]
    #[allow(clippy::too_many_arguments)]
    fn rgbd<'py>(
        py: Python<'py>,
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        width: usize,
        height: usize,
        depth_coefficient: Option<f64>,
        config: Option<Bound<'py, OdometryConfig>>,
        options: Option<&Bound<'py, PyDict>>,
    ) -> PyResult<Self> {
        let config = OdometryConfig::resolve(py, "Odometry.rgbd", config, options)?;
        let mut noise = RgbdNoise::default();
        noise.depth_coefficient = depth_coefficient.unwrap_or(noise.depth_coefficient);
        let camera = camera(fx, fy, cx, cy, noise.virtual_baseline_m, (width, height));
        Ok(Self::of(config.get().build(camera, Some(noise))?))
    }

    /// Takes the next RGB-D frame of an engine made by ``Odometry.rgbd``: a
    /// (height, width) uint8 gray image, its registered depth as a (height, width)
    /// float32 array in metres (0 or NaN: no depth), and the timestamp in seconds
    /// (strictly increasing). Returns its ``Frame``; errors as ``track``.
    fn track_rgbd(
        &self,
        py: Python<'_>,
        gray: &Bound<'_, PyAny>,
        depth: &Bound<'_, PyAny>,
        timestamp: f64,
    ) -> PyResult<Frame> {
        let g = ImageArray::<u8>::new("gray", gray, "uint8")?;
        let d = ImageArray::<f32>::new("depth", depth, "float32")?;
        let (gp, dp) = (g.pixels(), d.pixels());
        let input = RgbdInput {
            gray: gp.gray(),
            depth: dp.depth(),
            timestamp_s: timestamp,
        };
        self.run(py, move |engine| engine.track_rgbd(input))
    }

    /// The camera: fx, fy, cx, cy (pixels), baseline (metres), width, height.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera_dict(py, self.engine()?.camera())
    }

    /// The camera of the images the engine works on: ``camera`` halved (2x2 means) while
    /// its images have more than ``max_working_pixels`` pixels, doubled (bicubic) while
    /// they have fewer than ``min_working_pixels``. Everything else is in pixels of
    /// ``camera``.
    #[getter]
    fn working_camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera_dict(py, self.engine()?.working_camera())
    }

    /// The detector's name.
    #[getter]
    fn detector(&self) -> PyResult<&'static str> {
        Ok(self.engine()?.detector())
    }

    /// The estimator's name.
    #[getter]
    fn method(&self) -> PyResult<&'static str> {
        Ok(self.engine()?.estimator())
    }

    /// The self-calibration's current decision and its evidence (as the CLI's
    /// ``calibration.json``).
    #[getter]
    fn calibration<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        json_value(py, &calibration_json(&self.engine()?.calibration()))
    }

    /// Heap bytes of the engine's per-frame state (it does not grow with the frames).
    #[getter]
    fn state_bytes(&self) -> PyResult<usize> {
        Ok(self.engine()?.state_bytes())
    }

    fn __repr__(&self) -> PyResult<String> {
        let engine = self.engine()?;
        Ok(format!(
            "Odometry(detector={:?}, method={:?})",
            engine.detector(),
            engine.estimator()
        ))
    }
}
