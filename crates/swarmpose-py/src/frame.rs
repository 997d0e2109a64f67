//! `swarmpose.Frame`: the odometry engine's answer for one frame.

use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use swarmpose_odometry::{FrameResult, Status};
use swarmpose_vision::frontend::DisparityCorrection;

use crate::arrays::{matrix, transform, vector};

/// One frame's pose, its status, counts and stage timings.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct Frame {
    pub(crate) result: FrameResult,
}

#[pymethods]
impl Frame {
    /// 0-based index of the frame in the stream.
    #[getter]
    fn index(&self) -> usize {
        self.result.index
    }

    /// Timestamp, seconds, as given.
    #[getter]
    fn timestamp(&self) -> f64 {
        self.result.timestamp_s
    }

    /// Pose of the left camera in the left camera frame of the first frame (x right,
    /// y down, z forward, metres), 4x4.
    #[getter]
    fn pose<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        transform(py, &self.result.pose)
    }

    /// The motion from the previous frame ``T_{k-1,k}`` (this camera's pose in the
    /// previous one), 4x4; the identity for the first frame.
    #[getter]
    fn motion<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        transform(py, &self.result.motion)
    }

    /// The frame this frame was measured from (``None`` unless tracked): the previous
    /// one frame to frame; with ``window=K`` the window's oldest keyframe.
    #[getter]
    fn reference(&self) -> Option<usize> {
        self.result.reference
    }

    /// The motion measured from ``reference`` (this camera's pose in the reference
    /// camera, metres), 4x4; the identity unless tracked. With ``window=K`` the window
    /// may have revised the reference's pose since it was given out, so ``pose`` is not
    /// the reference's given-out pose times this motion.
    #[getter]
    fn measured_motion<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        transform(py, &self.result.measured_motion)
    }

    /// 6x6 covariance of ``measured_motion``, of ``(v, w)`` (metres, radians, in this
    /// camera's frame, ``T_true = T E(v, w)``), the self-calibrated disparity
    /// correction's uncertainty included; ``None`` when the motion was not refined.
    #[getter]
    fn covariance<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.result.covariance.as_ref().map(|c| matrix(py, c))
    }

    /// ``"first"``, ``"tracked"``, ``"constant-velocity (REASON)"`` or
    /// ``"lost (REASON)"``, as in the CLI's ``frames.csv``.
    #[getter]
    fn status(&self) -> String {
        self.result.status.text()
    }

    /// True when the motion was estimated from the images.
    #[getter]
    fn tracked(&self) -> bool {
        self.result.status.is_tracked()
    }

    /// True when the pose was predicted or held rather than measured.
    #[getter]
    fn predicted(&self) -> bool {
        !matches!(self.result.status, Status::First | Status::Tracked)
    }

    /// Feature counts: left_features, right_features, stereo_points, matches, inliers.
    #[getter]
    fn counts<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let c = &self.result.counts;
        let d = PyDict::new(py);
        d.set_item("left_features", c.left_features)?;
        d.set_item("right_features", c.right_features)?;
        d.set_item("stereo_points", c.stereo_points)?;
        d.set_item("matches", c.matches)?;
        d.set_item("inliers", c.inliers)?;
        Ok(d)
    }

    /// Wall-clock time of each stage, milliseconds (and their total).
    #[getter]
    fn times_ms<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let t = &self.result.times;
        let d = PyDict::new(py);
        d.set_item("load", t.load_ms)?;
        d.set_item("features", t.features_ms)?;
        d.set_item("stereo", t.stereo_ms)?;
        d.set_item("match", t.match_ms)?;
        d.set_item("estimate", t.estimate_ms)?;
        d.set_item("refine", t.refine_ms)?;
        d.set_item("window", t.window_ms)?;
        d.set_item("calibrate", t.calibrate_ms)?;
        d.set_item("total", t.total_ms())?;
        Ok(d)
    }

    /// The disparity correction applied to this frame: its terms, pixels.
    #[getter]
    fn correction<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        for (name, value) in DisparityCorrection::TERM_NAMES
            .iter()
            .zip(self.result.correction.coefficients())
        {
            d.set_item(format!("{name}_px"), value)?;
        }
        Ok(d)
    }

    /// True when the frame is a keyframe: with the sliding window, one of the window's
    /// keyframes (it moved beyond the measurement noise since the last one, or lost most
    /// of its tracks); without it, every frame later frames are measured from. False for
    /// a frame that was not tracked.
    #[getter]
    fn keyframe(&self) -> bool {
        self.result.keyframe
    }

    /// With the sliding window, its current estimate of each frame it holds, oldest
    /// first, this frame last: a list of ``(index, pose)`` with 4x4 poses as ``pose``
    /// (earlier frames as revised by this frame; a frame's last revision is the
    /// fixed-lag smoothed pose, see ``OdometryRun.smoothed_poses``). Empty without the
    /// window or for a frame that was not tracked.
    #[getter]
    fn window_poses<'py>(&self, py: Python<'py>) -> Vec<(usize, Bound<'py, PyArray2<f64>>)> {
        self.result
            .window_poses
            .iter()
            .map(|(i, p)| (*i, transform(py, p)))
            .collect()
    }

    /// True when the estimator found two distinct motions with comparable support (a
    /// large moving object, a repeating scene): the one nearer the constant-velocity
    /// prediction was taken, but the pose may be the other's; treat it with care.
    #[getter]
    fn ambiguous(&self) -> bool {
        self.result.ambiguous
    }

    /// The change of the rig's focal length applied to this frame, pixels of ``fx``
    /// (``fy`` in proportion; 0 unless self-calibration chose the ``focal-length`` cause).
    #[getter]
    fn focal_correction_px(&self) -> f64 {
        self.result.focal_px
    }

    /// The model of that correction (its causes, ``"none"`` for none).
    #[getter]
    fn correction_model(&self) -> String {
        self.result.correction_model.name()
    }

    /// The split-feature check of ``covariance`` (``split_check=True``; ``None`` without
    /// it, or when a half of the inliers was too small): a dict with ``difference`` (6,),
    /// the motion from the second half of the features minus the first's (metres,
    /// radians), ``covariance`` (6, 6), its covariance (the model's, with the systematic
    /// floor learned from the frames before added), ``nees``, the normalised squared
    /// difference under it (6 on average when the covariance is honest), ``model_nees``,
    /// the same under the model's covariance alone, and ``inliers``, each half's inlier
    /// count. See docs/covariance.md.
    #[getter]
    fn split<'py>(&self, py: Python<'py>) -> PyResult<Option<Bound<'py, PyDict>>> {
        let Some(s) = &self.result.split else {
            return Ok(None);
        };
        let d = PyDict::new(py);
        d.set_item("difference", vector(py, s.difference.as_slice()))?;
        d.set_item("covariance", matrix(py, &s.covariance))?;
        d.set_item("nees", s.nees)?;
        d.set_item("model_nees", s.model_nees)?;
        d.set_item("inliers", (s.inliers[0], s.inliers[1]))?;
        Ok(Some(d))
    }

    fn __repr__(&self) -> String {
        let t = self.result.pose.translation.vector;
        format!(
            "Frame(index={}, status={:?}, position=[{:.4}, {:.4}, {:.4}], inliers={})",
            self.result.index,
            self.result.status.text(),
            t.x,
            t.y,
            t.z,
            self.result.counts.inliers
        )
    }
}
