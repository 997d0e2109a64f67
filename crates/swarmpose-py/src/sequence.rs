//! `swarmpose.Sequence`: a recorded stereo sequence (KITTI, Karlsruhe, EuRoC) read by
//! the workspace's loaders, frame by frame as numpy images.

use std::path::PathBuf;

use numpy::{PyArray2, PyArray3};
use pyo3::exceptions::PyIndexError;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use swarmpose_datasets::StereoSequence;
use swarmpose_odometry::StereoCamera;
use swarmpose_runs::batch::camera_of;

use crate::arrays::{gray_image, transforms};
use crate::errors::dataset_error;

/// The left and right images of a frame.
type ImagePair<'py> = (Bound<'py, PyArray2<u8>>, Bound<'py, PyArray2<u8>>);

/// A stereo sequence directory: ``len(seq)`` frames, ``seq[i]`` the rectified
/// ``(left, right)`` uint8 images of frame ``i``.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct Sequence {
    pub(crate) inner: Box<dyn StereoSequence>,
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
    /// Opens `dir` (layout detected).
    pub(crate) fn open(dir: &std::path::Path) -> PyResult<Self> {
        let inner = swarmpose_datasets::open(dir).map_err(|e| dataset_error(&e))?;
        Ok(Self { inner })
    }
}

#[pymethods]
impl Sequence {
    /// Opens a KITTI odometry, Karlsruhe or EuRoC MAV sequence directory (the layout is
    /// detected). Raises ``FileNotFoundError`` for a missing directory, ``ValueError``
    /// for an unknown layout or malformed files.
    #[new]
    fn new(path: PathBuf) -> PyResult<Self> {
        Self::open(&path)
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

    /// The layout: ``"kitti"``, ``"karlsruhe"`` or ``"euroc"``.
    #[getter]
    fn layout(&self) -> &'static str {
        self.inner.layout()
    }

    /// The directory.
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
