//! # swarmpose-core
//!
//! Rigid motion between two sets of matched 3D points, `dst = R src + t`, with wrong
//! matches among them. This crate is the I/O-free core of swarmpose: geometry on
//! [`nalgebra`] types, a generic particle swarm optimizer, Arun's SVD least squares, and
//! the estimators behind one [`Estimator`] trait:
//!
//! | name | type | what it is |
//! |---|---|---|
//! | `pso` | [`PsoEstimator`] | robust PSO over unit quaternions with support counting on translation-free pairs, then SVD refinement |
//! | `pso-paper` | [`PsoPaperEstimator`] | the paper's PSO/SVD, literally (all-point centroids, eq. 13 and 15) |
//! | `svd` | [`SvdEstimator`] | Arun 1987 on all points, no outlier rejection |
//! | `msac` | [`MsacEstimator`] | Torr & Zisserman MSAC with 3-point samples and a final refit |
//!
//! Units: points and thresholds are in metres, angles in radians unless a name says
//! otherwise. Every rotation returned is proper (a unit quaternion), and every random
//! choice comes from a [`SeededRng`], so one seed gives one answer.
//!
//! ```
//! use nalgebra::{Isometry3, Point3, Vector3};
//! use swarmpose_core::{Correspondences, Estimator, SvdEstimator};
//!
//! let truth = Isometry3::new(Vector3::new(0.5, -0.2, 1.0), Vector3::new(0.0, 0.1, 0.05));
//! let src: Vec<Point3<f64>> = (0..20)
//!     .map(|i| Point3::new((i % 5) as f64, (i / 5) as f64, 5.0 + (i % 3) as f64))
//!     .collect();
//! let dst = src.iter().map(|p| truth * p).collect();
//! let data = Correspondences::new(src, dst)?;
//! let estimate = SvdEstimator::default().estimate_seeded(&data, 7)?;
//! assert!((estimate.transform.translation.vector - truth.translation.vector).norm() < 1e-9);
//! # Ok::<(), swarmpose_core::PoseError>(())
//! ```
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod arun;
pub mod error;
pub mod estimators;
pub mod geometry;
pub mod pso;
pub mod rng;
pub mod settings;
pub mod simd;
pub mod synthetic;

pub use arun::{arun, arun_weighted};
pub use error::{DegeneracyKind, PoseError};
pub use estimators::{
    CHI2_3_99, Diagnostics, Estimate, Estimator, EstimatorConfig, Method, MsacConfig,
    MsacEstimator, PsoEstimator, PsoEstimatorConfig, PsoPaperConfig, PsoPaperEstimator, RangeNoise,
    RunnerUp, SvdEstimator, Threshold, WlsEstimator, refine_mahalanobis,
};
pub use geometry::{Correspondences, MIN_CORRESPONDENCES};
pub use rng::SeededRng;
