//! # swarmpose-py
//!
//! The Python module `swarmpose` (built by maturin from `pyproject.toml` beside this
//! crate's manifest): the workspace's estimators, streaming odometry, sequence loaders
//! and trajectory metrics on numpy arrays. Nothing is implemented here twice: every
//! function converts arrays, calls the Rust crates and converts the answer back.
//!
//! | Python | Rust |
//! |---|---|
//! | `register` | [`swarmpose_core::Estimator::estimate_seeded`] |
//! | `OdometryConfig` | [`swarmpose_odometry::OdometryConfig`] |
//! | `Odometry`, `Odometry.track` | [`swarmpose_odometry::Odometry`], [`swarmpose_odometry::Odometry::track`] |
//! | `Odometry.rgbd`, `Odometry.track_rgbd` | [`swarmpose_odometry::Odometry::track_rgbd`] |
//! | `odometry` | [`swarmpose_runs::batch::run_sequence`], [`swarmpose_runs::batch::run_rgbd_sequence`] |
//! | `Sequence` | [`swarmpose_cli::commands::odometry::input::open_input`] (the command line's front door) |
//! | `evaluate` | [`swarmpose_eval::evaluate`] |
//! | `batch.run`, `batch.merge` | [`swarmpose_cli::batch`] |
//!
//! Errors become Python exceptions carrying the Rust error's one-line message
//! (`errors.rs`). Long computations release the GIL.
#![deny(missing_docs)]
#![warn(clippy::unwrap_used)]

mod args;
mod arrays;
mod batch;
mod errors;
mod evaluate;
mod frame;
mod methods;
mod odometry;
mod odometry_run;
mod options;
mod register;
mod sequence;

use pyo3::prelude::*;

/// The extension module `swarmpose._swarmpose`, re-exported by the package `swarmpose`.
#[pymodule]
fn _swarmpose(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add("EstimationError", py.get_type::<errors::EstimationError>())?;
    m.add("NotUsableError", py.get_type::<errors::NotUsableError>())?;
    m.add_function(wrap_pyfunction!(register::register, m)?)?;
    m.add_function(wrap_pyfunction!(register::register_timing, m)?)?;
    m.add_function(wrap_pyfunction!(odometry_run::odometry, m)?)?;
    m.add_function(wrap_pyfunction!(evaluate::evaluate, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_prepare, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_item, m)?)?;
    m.add_function(wrap_pyfunction!(batch::batch_merge, m)?)?;
    m.add_class::<register::Registration>()?;
    m.add_class::<register::RunnerUp>()?;
    m.add_class::<options::OdometryConfig>()?;
    m.add_class::<odometry::Odometry>()?;
    m.add_class::<odometry_run::OdometryRun>()?;
    m.add_class::<frame::Frame>()?;
    m.add_class::<sequence::Sequence>()?;
    m.add("METHODS", methods::names())?;
    Ok(())
}
