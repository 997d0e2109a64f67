//! `swarmpose.register`: the rigid motion `dst = R src + t` of two numpy point sets.

use crate::args::Seed;
use std::time::Instant;

use nalgebra::Isometry3;
use numpy::{PyArray1, PyArray2};
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use swarmpose_core::geometry::quaternion_wxyz;
use swarmpose_core::{Correspondences, Estimate};

use crate::arrays::{indices, matrices, matrix, points, transform, vector};
use crate::errors::pose_error;
use crate::methods;

/// The correspondences of the arguments of `register`.
fn correspondences(
    src: &Bound<'_, PyAny>,
    dst: &Bound<'_, PyAny>,
    src_cov: Option<&Bound<'_, PyAny>>,
    dst_cov: Option<&Bound<'_, PyAny>>,
) -> PyResult<Correspondences> {
    let s = points("src", src)?;
    let d = points("dst", dst)?;
    let data = Correspondences::new(s, d).map_err(|e| pose_error(&e))?;
    match (src_cov, dst_cov) {
        (None, None) => Ok(data),
        (Some(sc), Some(dc)) => {
            let n = data.len();
            let sc = matrices("src_cov", sc, n)?;
            let dc = matrices("dst_cov", dc, n)?;
            data.with_noise_covariance(sc, dc)
                .map_err(|e| pose_error(&e))
        }
        _ => Err(PyValueError::new_err(
            "src_cov and dst_cov go together: give both or neither",
        )),
    }
}

/// How the inliers were tested, as `swarmpose register` reports it.
fn noise_model(method: &str, data: &Correspondences, estimate: &Estimate) -> &'static str {
    match (method, data.noise_covariance().is_some()) {
        ("pso", true) => "covariance",
        ("svd", _) => "none",
        _ if estimate.diagnostics.range_noise.is_some() => "range",
        _ => "threshold",
    }
}

/// Estimates the rigid motion ``dst ≈ R @ src + t`` of matched 3D points.
///
/// ``src`` and ``dst`` are (N, 3) arrays of float32 or float64 (metres), in any memory
/// order; ``src_cov`` and ``dst_cov`` optional (N, 3, 3) noise covariances (m², each
/// point in its own frame), given together. ``method`` is one of ``swarmpose.METHODS``;
/// ``threshold`` the inlier threshold in metres (``pso`` estimates it from the data when
/// it is ``None``); ``seed`` seeds every random choice (one seed, one answer).
///
/// The GIL is released while the estimator runs.
///
/// Raises ``ValueError`` for wrong shapes, NaN, too few or degenerate points and bad
/// options, ``TypeError`` for a dtype that is not float, ``swarmpose.EstimationError``
/// when no pose has enough support.
#[pyfunction]
#[pyo3(signature = (src, dst, *, method = "pso", threshold = None, seed = Seed(0), src_cov = None, dst_cov = None))]
#[allow(clippy::too_many_arguments)]
pub(crate) fn register(
    py: Python<'_>,
    src: &Bound<'_, PyAny>,
    dst: &Bound<'_, PyAny>,
    method: &str,
    threshold: Option<f64>,
    seed: Seed,
    src_cov: Option<&Bound<'_, PyAny>>,
    dst_cov: Option<&Bound<'_, PyAny>>,
) -> PyResult<Registration> {
    let Seed(seed) = seed;
    let estimator = methods::estimator(method, threshold)?;
    let data = correspondences(src, dst, src_cov, dst_cov)?;
    if let Some(m) = swarmpose_core::arun::mirror_image(data.src(), data.dst()) {
        return Err(pyo3::exceptions::PyValueError::new_err(format!(
            "dst is a mirror image of src (a reflection fits it with an RMS of {:.3e}, the \
             best rotation {:.3e}): a reflection is not a rigid motion; check the sign of an axis",
            m.rms_reflection, m.rms_rotation
        )));
    }
    let estimate = py
        .detach(|| estimator.estimate_seeded(&data, seed))
        .map_err(|e| pose_error(&e))?;
    Ok(Registration {
        method: estimator.name(),
        seed,
        n: data.len(),
        noise_model: noise_model(estimator.name(), &data, &estimate),
        estimate,
    })
}

/// The Rust call that `register` wraps, timed in Rust: `repeats` runs of the
/// estimator on correspondences built once, the seconds of each (for
/// `bench/overhead.py`).
///
/// # Errors
/// As `register`.
#[pyfunction]
#[pyo3(name = "_register_timing", signature = (src, dst, *, method = "pso", seed = Seed(0), repeats = 1))]
pub(crate) fn register_timing(
    py: Python<'_>,
    src: &Bound<'_, PyAny>,
    dst: &Bound<'_, PyAny>,
    method: &str,
    seed: Seed,
    repeats: usize,
) -> PyResult<Vec<f64>> {
    let Seed(seed) = seed;
    let estimator = methods::estimator(method, None)?;
    let data = correspondences(src, dst, None, None)?;
    py.detach(|| {
        (0..repeats)
            .map(|_| {
                let t = Instant::now();
                let e = estimator.estimate_seeded(&data, seed);
                let s = t.elapsed().as_secs_f64();
                e.map(|_| s)
            })
            .collect::<Result<Vec<f64>, _>>()
    })
    .map_err(|e| pose_error(&e))
}

/// The rotation matrix of a motion, (3, 3).
fn rotation_matrix<'py>(py: Python<'py>, t: &Isometry3<f64>) -> Bound<'py, PyArray2<f64>> {
    matrix(py, t.rotation.to_rotation_matrix().matrix())
}

/// The result of ``swarmpose.register``: the motion ``dst ≈ R @ src + t`` (metres),
/// its inliers and the estimator's diagnostics.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct Registration {
    method: &'static str,
    seed: u64,
    n: usize,
    noise_model: &'static str,
    estimate: Estimate,
}

#[pymethods]
impl Registration {
    /// Rotation matrix R, (3, 3).
    #[getter]
    fn rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rotation_matrix(py, &self.estimate.transform)
    }

    /// Rotation as a unit quaternion ``[w, x, y, z]`` with ``w >= 0``, (4,).
    #[getter]
    fn quaternion_wxyz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector(py, &quaternion_wxyz(&self.estimate.transform.rotation))
    }

    /// Translation t, metres, (3,).
    #[getter]
    fn translation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v = self.estimate.transform.translation.vector;
        vector(py, &[v.x, v.y, v.z])
    }

    /// The 4x4 homogeneous transform ``[[R, t], [0, 1]]``.
    #[getter]
    fn transform<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        transform(py, &self.estimate.transform)
    }

    /// 0-based indices of the inlier correspondences, ascending (int64).
    #[getter]
    fn inliers<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        indices(py, &self.estimate.inliers)
    }

    /// Fraction of the correspondences that are inliers.
    #[getter]
    fn inlier_ratio(&self) -> f64 {
        self.estimate.inlier_ratio(self.n)
    }

    /// True when a second motion with comparable support was found (``pso`` only).
    #[getter]
    fn ambiguous(&self) -> bool {
        self.estimate.is_ambiguous()
    }

    /// That second motion, or ``None``.
    #[getter]
    fn runner_up(&self) -> Option<RunnerUp> {
        self.estimate
            .diagnostics
            .runner_up
            .as_ref()
            .map(|r| RunnerUp {
                transform: r.transform,
                inliers: r.inliers.clone(),
            })
    }

    /// The estimator's name.
    #[getter]
    fn method(&self) -> &'static str {
        self.method
    }

    /// The seed used.
    #[getter]
    fn seed(&self) -> u64 {
        self.seed
    }

    /// Number of correspondences given.
    #[getter]
    fn n_correspondences(&self) -> usize {
        self.n
    }

    /// How inliers were tested: ``"covariance"`` (Mahalanobis, ``pso`` with
    /// covariances), ``"range"`` (``pso`` without covariances, when the residuals chose a
    /// noise model growing with the range along the viewing ray over isotropic noise),
    /// ``"threshold"``, or ``"none"`` (``svd``).
    #[getter]
    fn noise_model(&self) -> &'static str {
        self.noise_model
    }

    /// Inlier threshold used, metres (``None`` for ``svd`` and with covariances).
    #[getter]
    fn threshold(&self) -> Option<f64> {
        self.estimate.diagnostics.threshold_m
    }

    /// Final cost, m²: the truncated quadratic cost over all correspondences.
    #[getter]
    fn final_cost(&self) -> f64 {
        self.estimate.diagnostics.final_cost
    }

    /// RMS of the inlier residuals ``|dst - (R src + t)|``, metres.
    #[getter]
    fn residual_rms(&self) -> f64 {
        self.estimate.diagnostics.residual_rms_m
    }

    /// Iterations of the estimator's main loop.
    #[getter]
    fn iterations(&self) -> usize {
        self.estimate.diagnostics.iterations
    }

    /// Evaluations of the cost over the data.
    #[getter]
    fn cost_evaluations(&self) -> u64 {
        self.estimate.diagnostics.cost_evaluations
    }

    /// Wall-clock time of the estimation in Rust, seconds.
    #[getter]
    fn elapsed_s(&self) -> f64 {
        self.estimate.diagnostics.elapsed.as_secs_f64()
    }

    fn __repr__(&self) -> String {
        let t = self.estimate.transform.translation.vector;
        format!(
            "Registration(method={:?}, inliers={}/{}, translation=[{:.6}, {:.6}, {:.6}], \
             angle={:.6} rad, ambiguous={})",
            self.method,
            self.estimate.inliers.len(),
            self.n,
            t.x,
            t.y,
            t.z,
            self.estimate.transform.rotation.angle(),
            if self.estimate.is_ambiguous() {
                "True"
            } else {
                "False"
            }
        )
    }
}

/// A second rigid motion found among the correspondences the estimate left over.
#[pyclass(frozen, module = "swarmpose")]
pub(crate) struct RunnerUp {
    transform: Isometry3<f64>,
    inliers: Vec<usize>,
}

#[pymethods]
impl RunnerUp {
    /// Rotation matrix, (3, 3).
    #[getter]
    fn rotation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rotation_matrix(py, &self.transform)
    }

    /// Rotation as ``[w, x, y, z]``, ``w >= 0``.
    #[getter]
    fn quaternion_wxyz<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        vector(py, &quaternion_wxyz(&self.transform.rotation))
    }

    /// Translation, metres, (3,).
    #[getter]
    fn translation<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<f64>> {
        let v = self.transform.translation.vector;
        vector(py, &[v.x, v.y, v.z])
    }

    /// The 4x4 homogeneous transform.
    #[getter]
    fn transform<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        transform(py, &self.transform)
    }

    /// Its inliers, 0-based, ascending (int64).
    #[getter]
    fn inliers<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray1<i64>> {
        indices(py, &self.inliers)
    }

    fn __repr__(&self) -> String {
        format!("RunnerUp(inliers={})", self.inliers.len())
    }
}
