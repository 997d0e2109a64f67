//! # swarmpose-sim
//!
//! The paper's simulation (section 6) as a library: seeded camera scenarios
//! ([`scenario`], [`outliers`]), their export in `gen_scenarios.py`'s files ([`export`]),
//! an experiment runner over every estimator ([`runner`]), and the tables and figures of
//! the results ([`report`], [`plots`]). [`simulate()`] is the whole job of
//! `swarmpose simulate`.
//!
//! ```
//! use swarmpose_core::{Estimator, MsacConfig, MsacEstimator};
//! use swarmpose_sim::{OutlierMode, SceneSpec, oracle_threshold};
//!
//! // Run seed 7: 2 cm noise, 60 % wrong matches, only points both cameras see.
//! let s = SceneSpec::default().scenario(7, 0.02, 0.6, OutlierMode::Random)?;
//! assert_eq!(s.n_outliers(), (0.6 * s.data.len() as f64).round() as usize);
//! let msac = MsacEstimator::new(MsacConfig::default().with_threshold(oracle_threshold(0.02)));
//! let est = msac.estimate_seeded(&s.data, 1)?;
//! let t_err = (est.transform.translation.vector - s.truth.translation.vector).norm();
//! assert!(t_err < 0.2);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod camera;
pub mod error;
pub mod outliers;
pub mod plots;
pub mod scenario;
pub mod stereo;

pub use camera::Pinhole;
pub use error::SimError;
pub use outliers::{OutlierMode, Scenario};
pub use scenario::{Geometry, SceneSpec};
pub use stereo::{StereoScenario, StereoSpec};
pub mod estimators;
pub mod experiment;
pub mod export;
pub mod metrics;
pub mod output;
pub mod runner;

pub use estimators::{EstimatorEntry, default_estimators, oracle_threshold};
pub use experiment::Experiment;
pub use metrics::RunRecord;
pub use runner::{Shard, run_experiment, run_experiment_shard, run_experiment_until};
pub mod report;
pub mod results;
pub mod runs_csv;
pub mod shard;
pub mod simulate;
pub mod stats;

pub use simulate::{SimOptions, SimOutcome, simulate, simulate_shard, simulate_until};
