//! Rust errors as Python exceptions, each with the Rust error's one-line message:
//! `ValueError` for input that cannot determine an answer (shapes, NaN, too few or
//! degenerate points, bad options), `FileNotFoundError`/`OSError` for paths,
//! [`EstimationError`] when the data ran and no pose had enough support.

use pyo3::exceptions::{PyFileNotFoundError, PyOSError, PyRuntimeError, PyValueError};
use pyo3::{PyErr, create_exception};
use swarmpose_core::PoseError;
use swarmpose_datasets::DatasetError;
use swarmpose_eval::EvalError;
use swarmpose_odometry::OdometryError;
use swarmpose_runs::RunError;
use swarmpose_vision::image::ImageError;

create_exception!(
    swarmpose,
    EstimationError,
    PyRuntimeError,
    "The estimator ran but found no pose with enough support (too many wrong matches)."
);

create_exception!(
    swarmpose,
    NotUsableError,
    EstimationError,
    "A run finished but fewer than half of its motions were tracked (the command line's \
     exit status 3); the exception's ``run`` holds every frame."
);

/// The Python exception type of an error.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Kind {
    Value,
    NotFound,
    Os,
}

impl Kind {
    fn of_io(kind: std::io::ErrorKind) -> Self {
        if kind == std::io::ErrorKind::NotFound {
            Kind::NotFound
        } else {
            Kind::Os
        }
    }

    fn of_dataset(e: &DatasetError) -> Self {
        match e {
            DatasetError::Missing { .. } => Kind::NotFound,
            DatasetError::Io { source, .. }
            | DatasetError::Image(ImageError::Read { source, .. }) => Kind::of_io(source.kind()),
            _ => Kind::Value,
        }
    }

    fn of_eval(e: &EvalError) -> Self {
        match e {
            EvalError::Io { source, .. } => Kind::of_io(source.kind()),
            _ => Kind::Value,
        }
    }

    fn err(self, message: String) -> PyErr {
        match self {
            Kind::Value => PyValueError::new_err(message),
            Kind::NotFound => PyFileNotFoundError::new_err(message),
            Kind::Os => PyOSError::new_err(message),
        }
    }
}

/// An estimator's error.
pub(crate) fn pose_error(e: &PoseError) -> PyErr {
    match e {
        PoseError::InsufficientSupport { .. } => EstimationError::new_err(e.to_string()),
        _ => PyValueError::new_err(e.to_string()),
    }
}

/// A sequence loader's error.
pub(crate) fn dataset_error(e: &DatasetError) -> PyErr {
    Kind::of_dataset(e).err(e.to_string())
}

/// A trajectory reader's or evaluator's error.
pub(crate) fn eval_error(e: &EvalError) -> PyErr {
    Kind::of_eval(e).err(e.to_string())
}

/// The odometry engine's error (always bad input: `ValueError`).
pub(crate) fn odometry_error(e: &OdometryError) -> PyErr {
    PyValueError::new_err(e.to_string())
}

/// The error of a run over a sequence: the type of its cause, the whole message (which
/// names the frame of a run), then `more` (what the run kept).
pub(crate) fn run_error_then(e: &RunError, more: &str) -> PyErr {
    let mut root = e;
    while let RunError::AtFrame { source, .. } = root {
        root = source;
    }
    let kind = match root {
        RunError::Dataset(d) => Kind::of_dataset(d),
        RunError::Eval(ev) => Kind::of_eval(ev),
        RunError::Write { .. } => Kind::Os,
        _ => Kind::Value,
    };
    kind.err(format!("{e}{more}"))
}
