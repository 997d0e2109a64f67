//! Method names to estimators: the one function through which the Python package builds
//! an estimator, so that a change of the workspace's registry of estimator names is a
//! change of this function alone.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use swarmpose_core::{
    Estimator, MsacConfig, MsacEstimator, PsoEstimator, PsoEstimatorConfig, PsoPaperConfig,
    PsoPaperEstimator, SvdEstimator, Threshold,
};

/// The names `method=` accepts, as on the command line (`swarmpose register --method`).
pub(crate) const NAMES: [&str; 4] = ["pso", "pso-paper", "svd", "msac"];

/// The estimator called `method` with its default configuration, and the inlier
/// threshold `threshold_m` (metres) when given: `pso` estimates it from the data
/// otherwise; `svd` has none.
///
/// # Errors
/// `ValueError` for an unknown name, a threshold that is not finite and positive, or a
/// threshold for `svd`.
pub(crate) fn estimator(method: &str, threshold_m: Option<f64>) -> PyResult<Box<dyn Estimator>> {
    if let Some(d) = threshold_m
        && !(d.is_finite() && d > 0.0)
    {
        return Err(PyValueError::new_err(format!(
            "threshold {d}: it must be a positive, finite number of metres"
        )));
    }
    Ok(match method {
        "pso" => {
            let mut c = PsoEstimatorConfig::default();
            if let Some(d) = threshold_m {
                c.threshold = Threshold::Fixed(d);
            }
            Box::new(PsoEstimator::new(c))
        }
        "pso-paper" => {
            let mut c = PsoPaperConfig::default();
            c.threshold_m = threshold_m.unwrap_or(c.threshold_m);
            Box::new(PsoPaperEstimator::new(c))
        }
        "msac" => {
            let mut c = MsacConfig::default();
            c.threshold_m = threshold_m.unwrap_or(c.threshold_m);
            Box::new(MsacEstimator::new(c))
        }
        "svd" if threshold_m.is_some() => {
            return Err(PyValueError::new_err(
                "threshold does not apply to method svd",
            ));
        }
        "svd" => Box::new(SvdEstimator),
        other => {
            return Err(PyValueError::new_err(format!(
                "unknown method {other:?}: one of {}",
                NAMES.join(", ")
            )));
        }
    })
}
