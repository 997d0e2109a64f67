//! Arguments as Python gives them, converted with errors that name the argument (pyo3's
//! own conversions raise a bare `OverflowError` for `seed=-1`, or an internal message
//! about enum variants for a wrong-length tuple).

use pyo3::exceptions::{PyTypeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::PyInt;

/// A seed: a Python `int` from 0 to 2**64 - 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, IntoPyObject)]
pub(crate) struct Seed(pub(crate) u64);

impl<'a, 'py> FromPyObject<'a, 'py> for Seed {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        if !obj.is_instance_of::<PyInt>() {
            return Err(PyTypeError::new_err(format!(
                "seed must be an int, not {}",
                obj.get_type().name()?
            )));
        }
        obj.extract::<u64>().map(Seed).map_err(|_| {
            PyValueError::new_err(format!(
                "seed must be an integer from 0 to 2**64 - 1, got {}",
                obj.repr()
                    .map_or_else(|_| "?".to_owned(), |r| r.to_string())
            ))
        })
    }
}

/// A fixed disparity correction as Python gives it: `(offset, quadratic)` or
/// `(offset, quadratic, linear)`, pixels; the same tuple back.
#[derive(Debug, Clone, Copy, PartialEq, IntoPyObject)]
pub(crate) enum FixedCorrection {
    /// Offset and the term in x².
    Two((f64, f64)),
    /// Offset, the term in x² and the term in x.
    Three((f64, f64, f64)),
}

impl<'a, 'py> FromPyObject<'a, 'py> for FixedCorrection {
    type Error = PyErr;

    fn extract(obj: Borrowed<'a, 'py, PyAny>) -> PyResult<Self> {
        const WHAT: &str = "disparity_correction must be (offset, quadratic) or (offset, \
                            quadratic, linear), numbers of pixels";
        let terms: Vec<f64> = obj.extract().map_err(|_| {
            PyTypeError::new_err(format!(
                "{WHAT}, not {}",
                obj.get_type()
                    .name()
                    .map_or_else(|_| "?".to_owned(), |n| n.to_string())
            ))
        })?;
        match terms[..] {
            [a, q] => Ok(Self::Two((a, q))),
            [a, q, l] => Ok(Self::Three((a, q, l))),
            _ => Err(PyValueError::new_err(format!(
                "{WHAT}: got {} number(s)",
                terms.len()
            ))),
        }
    }
}
