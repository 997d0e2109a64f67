//! `swarmpose.Sequence`: a recorded stereo sequence (KITTI, Karlsruhe, EuRoC, or a ROS 2
//! bag) read by the workspace's loaders, frame by frame as numpy images. It is opened by
//! [`swarmpose_ros::open_stereo`], the front door of `swarmpose odometry`: the same
//! inputs, the same errors.

use std::path::PathBuf;

use numpy::{PyArray2, PyArray3};
use pyo3::exceptions::{PyIndexError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use swarmpose_datasets::StereoSequence;
use swarmpose_odometry::StereoCamera;
use swarmpose_ros::{BagInfo, StereoOptions, open_stereo};
use swarmpose_runs::batch::camera_of;

use crate::arrays::{gray_image, transforms};
use crate::errors::dataset_error;

/// The left and right images of a frame.
type ImagePair<'py> = (Bound<'py, PyArray2<u8>>, Bound<'py, PyArray2<u8>>);

/// A stereo sequence directory or ROS 2 bag: ``len(seq)`` frames, ``seq[i]`` the
/// rectified ``(left, right)`` uint8 images of frame ``i``.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct Sequence {
    pub(crate) inner: Box<dyn StereoSequence>,
    /// What a bag adds (its topics, stamps, unpaired images), for a bag.
    pub(crate) bag: Option<BagInfo>,
}

/// How to read a bag: the topics named or found, the stamp tolerance (milliseconds).
#[derive(Debug, Clone, Default)]
pub(crate) struct BagArgs {
    pub(crate) left: Option<String>,
    pub(crate) right: Option<String>,
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
        let opts = StereoOptions::with_tolerance_ms(bag.left, bag.right, bag.stamp_tolerance)
            .map_err(|e| PyValueError::new_err(format!("stamp_tolerance: {e}")))?;
        let opened = open_stereo(path, &opts).map_err(|e| dataset_error(&e))?;
        Ok(Self {
            inner: opened.sequence,
            bag: opened.bag,
        })
    }
}

#[pymethods]
impl Sequence {
    /// Opens a KITTI odometry, Karlsruhe or EuRoC MAV sequence directory (the layout is
    /// detected) or a ROS 2 bag (an ``.mcap`` or ``.db3`` file, or a rosbag2 folder with
    /// ``metadata.yaml``), as ``swarmpose odometry`` does. For a bag: ``left`` and
    /// ``right`` name the image topics (found when not given), ``stamp_tolerance`` is the
    /// largest difference of a pair's header stamps (milliseconds). Raises
    /// ``FileNotFoundError`` for a missing directory, ``ValueError`` for an unknown
    /// layout, malformed files or an unusable bag (the command line's message).
    #[new]
    #[pyo3(signature = (path, *, left = None, right = None, stamp_tolerance = 0.0))]
    fn new(
        path: PathBuf,
        left: Option<String>,
        right: Option<String>,
        stamp_tolerance: f64,
    ) -> PyResult<Self> {
        Self::open(
            &path,
            BagArgs {
                left,
                right,
                stamp_tolerance,
            },
        )
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    /// The ``(left, right)`` images of frame ``i`` as (height, width) uint8 arrays.
    fn __getitem__<'py>(&self, py: Python<'py>, i: isize) -> PyResult<ImagePair<'py>> {
        let n = self.inner.len();
        let k = if i < 0 { i + n as isize } else { i };
        let Ok(k) = usize::try_from(k) else {
            return Err(PyIndexError::new_err(format!(
                "frame {i} of a sequence of {n}"
            )));
        };
        if k >= n {
            return Err(PyIndexError::new_err(format!(
                "frame {i} of a sequence of {n}"
            )));
        }
        let pair = py
            .detach(|| self.inner.frame(k))
            .map_err(|e| dataset_error(&e))?;
        Ok((
            gray_image(py, pair.left.width, pair.left.height, &pair.left.data)?,
            gray_image(py, pair.right.width, pair.right.height, &pair.right.data)?,
        ))
    }

    /// The layout: ``"kitti"``, ``"karlsruhe"``, ``"euroc"`` or ``"ros2 bag"``.
    #[getter]
    fn layout(&self) -> &'static str {
        self.inner.layout()
    }

    /// The header stamp of each frame's left image (nanoseconds) for a bag, else
    /// ``None``.
    #[getter]
    fn stamps_ns(&self) -> Option<Vec<i64>> {
        self.bag.as_ref().map(|b| b.stamps_ns.clone())
    }

    /// The ``(left, right)`` image topics of a bag, else ``None``.
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

    /// The rectified camera: fx, fy, cx, cy (pixels), baseline (metres), width, height.
    #[getter]
    fn camera<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        camera_dict(py, &camera_of(self.inner.as_ref()))
    }

    /// Ground-truth poses of the left camera in the first frame's, (N, 4, 4), or
    /// ``None``.
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
