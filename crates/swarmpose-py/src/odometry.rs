//! `swarmpose.Odometry`: the streaming engine, frames in, poses out (stereo pairs, or
//! RGB-D frames for an engine made by `Odometry.rgbd`).

use std::path::PathBuf;

use pyo3::prelude::*;
use pyo3::types::PyDict;
use swarmpose_odometry::batch::camera_of;
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::output::calibration_json;
use swarmpose_odometry::{DepthView, RgbdInput, StereoCamera, StereoInput};
use swarmpose_vision::features::GrayView;
use swarmpose_vision::stereo::RectifiedStereo;

use crate::arrays::ImageArray;
use crate::errors::odometry_error;
use crate::evaluate::json_value;
use crate::frame::Frame;
use crate::options::Options;
use crate::sequence::{Sequence, camera_dict};

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
    /// may correct, e.g. ``"principal-point+yaw+focal"``, or ``"none"``; default as the
    /// command line), ``disparity_correction`` (a fixed ``(offset, quadratic)`` in
    /// pixels instead), ``min_inliers``, ``seed`` (frame k uses seed + k), ``window``
    /// (keyframes of the sliding-window bundle adjustment; 0: frame to frame; default as the
    /// command line, 10), ``marginalise`` (what happens to the window's oldest keyframe when
    /// it leaves: ``"off"``, the default, ``"finished"`` or ``"all"``; see docs/window.md),
    /// ``max_working_pixels`` and ``min_working_pixels`` (stereo images are halved while
    /// they have more pixels than the first, 1 500 000 by default, and doubled while they
    /// have fewer than the second, 0 by default: never; see ``working_camera``).
    #[new]
    #[pyo3(signature = (fx, fy, cx, cy, baseline, width, height, *, method = "pso", threshold = None,
        detector = "orb", refine = true, calibrate = None, disparity_correction = None,
        min_inliers = None, seed = 0, window = None, marginalise = None, max_working_pixels = None, min_working_pixels = None))]
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
        window: Option<usize>,
        marginalise: Option<&str>,
        max_working_pixels: Option<usize>,
        min_working_pixels: Option<usize>,
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
            window,
            marginalise,
            max_working_pixels,
            min_working_pixels,
            rgbd: None,
        };
        Ok(Self {
            inner: options.build(camera)?,
        })
    }

    /// An engine for the camera of a sequence directory (its calibration and image
    /// size); options as for ``Odometry(...)``.
    #[staticmethod]
    #[pyo3(signature = (sequence_dir, *, method = "pso", threshold = None, detector = "orb",
        refine = true, calibrate = None, disparity_correction = None, min_inliers = None, seed = 0,
        window = None, marginalise = None, max_working_pixels = None, min_working_pixels = None))]
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
        window: Option<usize>,
        marginalise: Option<&str>,
        max_working_pixels: Option<usize>,
        min_working_pixels: Option<usize>,
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
            window,
            marginalise,
            max_working_pixels,
            min_working_pixels,
            rgbd: None,
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
        let l = ImageArray::<u8>::new("left", left, "uint8")?;
        let r = ImageArray::<u8>::new("right", right, "uint8")?;
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

    /// An engine for an RGB-D camera (focal lengths and principal point in pixels,
    /// images of ``width`` x ``height``): frames go to ``track_rgbd``. Depth noise
    /// ``sigma_z = depth_coefficient * z**2`` (1/m; the Kinect v1's by default); ORB
    /// features, no disparity correction; other options as for ``Odometry(...)``.
    #[staticmethod]
    #[pyo3(signature = (fx, fy, cx, cy, width, height, *, depth_coefficient = None,
        method = "pso", threshold = None, refine = true, min_inliers = None, seed = 0,
        window = None, marginalise = None))]
    #[allow(clippy::too_many_arguments)]
    fn rgbd(
        fx: f64,
        fy: f64,
        cx: f64,
        cy: f64,
        width: usize,
        height: usize,
        depth_coefficient: Option<f64>,
        method: &str,
        threshold: Option<f64>,
        refine: bool,
        min_inliers: Option<usize>,
        seed: u64,
        window: Option<usize>,
        marginalise: Option<&str>,
    ) -> PyResult<Self> {
        let mut noise = RgbdNoise::default();
        noise.depth_coefficient = depth_coefficient.unwrap_or(noise.depth_coefficient);
        let camera = StereoCamera {
            rig: RectifiedStereo {
                fx,
                fy,
                cx,
                cy,
                baseline_m: noise.virtual_baseline_m,
            },
            width,
            height,
        };
        let options = Options {
            method,
            threshold,
            detector: "orb",
            refine,
            calibrate: None,
            disparity_correction: None,
            min_inliers,
            seed,
            window,
            marginalise,
            max_working_pixels: None,
            min_working_pixels: None,
            rgbd: Some(noise),
        };
        Ok(Self {
            inner: options.build(camera)?,
        })
    }

    /// Takes the next RGB-D frame of an engine made by ``Odometry.rgbd``: a
    /// (height, width) uint8 gray image, its registered depth as a (height, width)
    /// float32 array in metres (0 or NaN: no depth), and the timestamp in seconds
    /// (strictly increasing). Returns its ``Frame``; errors as ``track``.
    fn track_rgbd(
        &mut self,
        py: Python<'_>,
        gray: &Bound<'_, PyAny>,
        depth: &Bound<'_, PyAny>,
        timestamp: f64,
    ) -> PyResult<Frame> {
        let g = ImageArray::<u8>::new("gray", gray, "uint8")?;
        let d = ImageArray::<f32>::new("depth", depth, "float32")?;
        let ((gw, gh), (dw, dh)) = (g.size(), d.size());
        let (gp, dp) = (g.pixels(), d.pixels());
        let input = RgbdInput {
            gray: GrayView {
                width: gw,
                height: gh,
                data: &gp,
            },
            depth: DepthView {
                width: dw,
                height: dh,
                data: &dp,
            },
            timestamp_s: timestamp,
        };
        let engine = &mut self.inner;
        let result = py
            .detach(move || engine.track_rgbd(input))
            .map_err(|e| odometry_error(&e))?;
        Ok(Frame { result })
    }

    /// The camera: fx, fy, cx, cy (pixels), baseline (metres), width, height.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera_dict(py, self.inner.camera())
    }

    /// The camera of the images the engine works on: ``camera`` halved (2x2 means) while
    /// its images have more than ``max_working_pixels`` pixels, doubled (bicubic) while
    /// they have fewer than ``min_working_pixels``. Everything else is in pixels of
    /// ``camera``.
    #[getter]
    fn working_camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera_dict(py, self.inner.working_camera())
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
        json_value(py, &calibration_json(&self.inner.calibration()))
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
