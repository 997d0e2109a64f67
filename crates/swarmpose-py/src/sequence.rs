//! `swarmpose.Sequence`: a recorded sequence (KITTI, Karlsruhe, EuRoC, a TUM RGB-D folder,
//! or a ROS 2 bag, stereo or RGB-D) read by the workspace's loaders, frame by frame as
//! numpy images. It is opened by [`swarmpose_cli::commands::odometry::input::open_input`],
//! the front door of `swarmpose odometry`: the same inputs, the same errors.

use std::ops::ControlFlow;
use std::path::PathBuf;

use numpy::PyArray3;
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyTuple};
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::{FrameResult, Odometry, RunEnd, StereoCamera};
use swarmpose_ros::{BagInfo, Input, StereoOptions};
use swarmpose_runs::RunError;
use swarmpose_runs::batch::{camera_of, rgbd_camera, run_rgbd_sequence, run_sequence};

use crate::arrays::{image_array, transforms};
use crate::errors::{dataset_error, run_error_then};
use crate::options::OdometryConfig;

/// A stereo or RGB-D sequence directory or ROS 2 bag: ``len(seq)`` frames, ``seq[i]``
/// the rectified ``(left, right)`` uint8 images of frame ``i`` (RGB-D: the ``(gray,
/// depth)`` images, uint8 and float32 metres).
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct Sequence {
    pub(crate) inner: Input,
    /// What a bag adds (its topics, stamps, unpaired images), for a bag.
    pub(crate) bag: Option<BagInfo>,
}

/// How to read a bag: the topics named or found, the stamp tolerance (milliseconds).
#[derive(Debug, Clone, Default)]
pub(crate) struct BagArgs {
    pub(crate) left: Option<String>,
    pub(crate) right: Option<String>,
    pub(crate) depth: Option<String>,
    pub(crate) stamp_tolerance: f64,
}

/// The camera as a dict: fx, fy, cx, cy (pixels), baseline (metres), width, height.
pub(crate) fn camera_dict<'py>(py: Python<'py>, c: &StereoCamera) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("fx", c.rig.fx)?;
    d.set_item("fy", c.rig.fy)?;
    d.set_item("cx", c.rig.cx)?;
    d.set_item("cy", c.rig.cy)?;
    d.set_item("baseline", c.rig.baseline_m)?;
    d.set_item("width", c.width)?;
    d.set_item("height", c.height)?;
    Ok(d)
}

impl Sequence {
    /// Opens `path` (a bag, or a folder whose layout is detected) as `swarmpose odometry`
    /// does.
    pub(crate) fn open(path: &std::path::Path, bag: BagArgs) -> PyResult<Self> {
        let mut opts = StereoOptions::with_tolerance_ms(bag.left, bag.right, bag.stamp_tolerance)
            .map_err(|e| PyValueError::new_err(format!("stamp_tolerance: {e}")))?;
        opts.depth = bag.depth;
        let opened = swarmpose_cli::commands::odometry::input::open_input(path, &opts)
            .map_err(|e| run_error_then(&e, ""))?;
        Ok(Self {
            inner: opened.input,
            bag: opened.bag,
        })
    }

    /// The engine's camera: the stereo rig, or the RGB-D camera with the RGB-D engine's
    /// virtual baseline.
    fn engine_camera(&self) -> PyResult<StereoCamera> {
        match &self.inner {
            Input::Stereo(s) => Ok(camera_of(s.as_ref())),
            Input::Rgbd(s) => rgbd_camera(s.as_ref()).map_err(|e| run_error_then(&e, "")),
        }
    }

    /// An engine for this sequence's camera, as `swarmpose odometry` makes it (RGB-D: with
    /// the default depth noise).
    pub(crate) fn engine(&self, config: &OdometryConfig) -> PyResult<Odometry> {
        let rgbd = matches!(self.inner, Input::Rgbd(_)).then(RgbdNoise::default);
        config.build(self.engine_camera()?, rgbd)
    }

    /// Runs `engine` over every frame, as `swarmpose odometry` does on one thread: a
    /// stereo frame at its timestamp (else `i * frame_period_s`), an RGB-D frame at its
    /// own time.
    pub(crate) fn run(
        &self,
        engine: &mut Odometry,
        frame_period_s: f64,
        on_frame: &mut dyn FnMut(&FrameResult) -> ControlFlow<()>,
    ) -> Result<RunEnd, RunError> {
        match &self.inner {
            Input::Stereo(s) => run_sequence(s.as_ref(), engine, frame_period_s, on_frame),
            Input::Rgbd(s) => run_rgbd_sequence(s.as_ref(), engine, on_frame),
        }
    }
}

#[pymethods]
impl Sequence {
    /// Opens a KITTI odometry, Karlsruhe or EuRoC MAV sequence directory or a TUM RGB-D
    /// folder (the layout is detected) or a ROS 2 bag (an ``.mcap`` or ``.db3`` file, or
    /// a rosbag2 folder with ``metadata.yaml``; stereo, or RGB-D: one colour and one
    /// depth camera), as ``swarmpose odometry`` does. For a bag: ``left`` and ``right``
    /// name the image topics (RGB-D: ``depth`` the depth topic and ``left`` the colour
    /// one; found when not given), ``stamp_tolerance`` is the largest difference of a
    /// pair's header stamps (milliseconds). Raises ``FileNotFoundError`` for a missing
    /// directory, ``ValueError`` for an unknown layout, malformed files or an unusable
    /// bag (the command line's message).
    #[new]
    #[pyo3(signature = (path, *, left = None, right = None, depth = None, stamp_tolerance = 0.0))]
    fn new(
        path: PathBuf,
        left: Option<String>,
        right: Option<String>,
        depth: Option<String>,
        stamp_tolerance: f64,
    ) -> PyResult<Self> {
        Self::open(
            &path,
            BagArgs {
                left,
                right,
                depth,
                stamp_tolerance,
            },
        )
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// Frame ``i``: the ``(left, right)`` images as (height, width) uint8 arrays; for an
    /// RGB-D input the ``(gray, depth)`` images, (height, width) uint8 and float32
    /// (metres, 0 where there is no depth).
    fn __getitem__<'py>(&self, py: Python<'py>, i: isize) -> PyResult<Bound<'py, PyAny>> {
        let n = self.inner.len();
        let k = if i < 0 { i + n as isize } else { i };
        let k = usize::try_from(k)
            .ok()
            .filter(|&k| k < n)
            .ok_or_else(|| PyIndexError::new_err(format!("frame {i} of a sequence of {n}")))?;
        match &self.inner {
            Input::Stereo(s) => {
                let pair = py.detach(|| s.frame(k)).map_err(|e| dataset_error(&e))?;
                let (l, r) = (&pair.left, &pair.right);
                let left = image_array(py, l.width, l.height, &l.data)?;
                let right = image_array(py, r.width, r.height, &r.data)?;
                Ok(PyTuple::new(py, [left.into_any(), right.into_any()])?.into_any())
            }
            Input::Rgbd(s) => {
                let f = py.detach(|| s.frame(k)).map_err(|e| dataset_error(&e))?;
                let (w, h) = (f.gray.width, f.gray.height);
                let gray = image_array(py, w, h, &f.gray.data)?;
                let depth = image_array(py, w, h, &f.depth_m)?;
                Ok(PyTuple::new(py, [gray.into_any(), depth.into_any()])?.into_any())
            }
        }
    }

    /// The layout: ``"kitti"``, ``"karlsruhe"``, ``"euroc"``, ``"tum rgb-d"``, ``"ros2
    /// bag"`` or ``"ros2 bag, rgb-d"``.
    #[getter]
    fn layout(&self) -> &'static str {
        self.inner.layout()
    }

    /// True for an RGB-D input (frames of gray and depth images).
    #[getter]
    fn rgbd(&self) -> bool {
        matches!(self.inner, Input::Rgbd(_))
    }

    /// The header stamp of each frame's left (RGB-D: colour) image (nanoseconds) for a
    /// bag, else ``None``.
    #[getter]
    fn stamps_ns(&self) -> Option<Vec<i64>> {
        self.bag.as_ref().map(|b| b.stamps_ns.clone())
    }

    /// The ``(left, right)`` image topics of a bag (RGB-D: ``(colour, depth)``), else
    /// ``None``.
    #[getter]
    fn topics(&self) -> Option<(String, String)> {
        self.bag.as_ref().map(|b| b.topics.clone())
    }

    /// The images of a bag that found no partner (one line each: topic, message,
    /// stamp); empty for a folder.
    #[getter]
    fn unpaired(&self) -> Vec<String> {
        self.bag.as_ref().map_or_else(Vec::new, |b| {
            b.unpaired.iter().map(ToString::to_string).collect()
        })
    }

    /// The directory (or bag).
    #[getter]
    fn root(&self) -> PathBuf {
        self.inner.root().to_owned()
    }

    /// The rectified camera: fx, fy, cx, cy (pixels), baseline (metres; ``None`` for
    /// RGB-D), width, height.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = camera_dict(py, &self.engine_camera()?)?;
        if self.rgbd() {
            // The engine's virtual baseline is not the camera's.
            d.set_item("baseline", py.None())?;
        }
        Ok(d)
    }

    /// Ground-truth poses of the left (RGB-D: colour) camera in the first frame's,
    /// (N, 4, 4), or ``None``.
    #[getter]
    fn ground_truth<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray3<f64>>> {
        self.inner.ground_truth().map(|g| transforms(py, g))
    }

    fn __repr__(&self) -> String {
        format!(
            "Sequence({:?}, layout={:?}, frames={})",
            self.inner.root().display().to_string(),
            self.inner.layout(),
            self.inner.len()
        )
    }
}
