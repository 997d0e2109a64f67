//! # swarmpose-sim
//!
//! The paper's simulation (section 6) as a library: seeded camera scenarios
//! ([`scenario`], [`outliers`]), their export in `gen_scenarios.py`'s files ([`export`]),
//! an experiment runner over every estimator ([`runner`]), and the tables and figures of
//! the results ([`report`], [`plots`]).
#![deny(missing_docs)]
#![warn(clippy::unwrap_used)]

pub mod camera;
pub mod error;
pub mod outliers;
pub mod plots;
pub mod scenario;

pub use camera::Pinhole;
pub use error::SimError;
pub use outliers::{OutlierMode, Scenario};
pub use scenario::{Geometry, SceneSpec};
pub mod estimators;
pub mod experiment;
pub mod export;
pub mod metrics;
pub mod output;
pub mod runner;

pub use estimators::{EstimatorEntry, default_estimators, oracle_threshold};
pub use experiment::Experiment;
pub use metrics::RunRecord;
pub use runner::run_experiment;
pub mod report;
pub mod runs_csv;
pub mod simulate;
pub mod stats;

pub use simulate::{SimOptions, SimOutcome, simulate};
