//! Method names to estimators: the one function through which the Python package builds
//! an estimator, so that a change of the workspace's registry of estimator names is a
//! change of this function alone.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use swarmpose_core::{Estimator, EstimatorConfig, Method};

/// The names `method=` accepts: the workspace's one registry
/// ([`swarmpose_core::Method`]), as on the command line (`swarmpose register --method`).
pub(crate) fn names() -> Vec<&'static str> {
    Method::ALL.iter().map(|m| m.name()).collect()
}

/// The estimator called `method` with its default configuration, and the inlier
/// threshold `threshold_m` (metres) when given: `pso` estimates it from the data
/// otherwise; `svd` and `wls` have none.
///
/// # Errors
/// `ValueError` for an unknown name, a threshold that is not finite and positive, or a
/// threshold for a method without one.
pub(crate) fn estimator(method: &str, threshold_m: Option<f64>) -> PyResult<Box<dyn Estimator>> {
    if let Some(d) = threshold_m
        && !(d.is_finite() && d > 0.0)
    {
        return Err(PyValueError::new_err(format!(
            "threshold {d}: it must be a positive, finite number of metres"
        )));
    }
    let Some(m) = Method::from_name(method) else {
        return Err(PyValueError::new_err(format!(
            "unknown method {method:?}: one of {}",
            names().join(", ")
        )));
    };
    if threshold_m.is_some() && !m.uses_threshold() {
        return Err(PyValueError::new_err(format!(
            "threshold does not apply to method {method}"
        )));
    }
    Ok(m.build(threshold_m))
}

/// The estimator settings of `base` (a run configuration's) with `method` (its defaults,
/// when it differs from `base`'s) and the threshold `threshold_m` applied over them.
///
/// # Errors
/// As [`estimator`].
pub(crate) fn configure(
    base: EstimatorConfig,
    method: Option<&str>,
    threshold_m: Option<f64>,
) -> PyResult<EstimatorConfig> {
    let name = method.unwrap_or(base.method().name());
    // Checks the name, the threshold and that the method takes one.
    estimator(name, threshold_m)?;
    let m = Method::from_name(name).unwrap_or(base.method());
    let base = if m == base.method() {
        base
    } else {
        EstimatorConfig::of(m)
    };
    Ok(match (base, threshold_m) {
        (EstimatorConfig::Pso(c), Some(d)) => EstimatorConfig::Pso(c.with_threshold(d)),
        (EstimatorConfig::PsoPaper(c), Some(d)) => EstimatorConfig::PsoPaper(c.with_threshold(d)),
        (EstimatorConfig::Msac(c), Some(d)) => EstimatorConfig::Msac(c.with_threshold(d)),
        (other, _) => other,
    })
}
