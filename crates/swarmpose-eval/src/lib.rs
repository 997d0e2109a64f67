//! # swarmpose-eval
//!
//! Trajectories and how far they are from the truth: KITTI and TUM trajectory files
//! ([`trajectory`]), association of estimated and true poses by index or timestamp
//! ([`associate`]), and the metrics ([`metrics`]): the paper's rotation error eq. (20)
//! per frame and its RMS (Table I), ATE raw and after Umeyama SE(3) alignment, RPE,
//! final drift, and the KITTI devkit segment errors ([`segments`]). ATE and RPE follow evo's
//! definitions (`evo_ape`, `evo_rpe --delta 1 --delta_unit f`).
//!
//! ```
//! use nalgebra::Isometry3;
//! use swarmpose_eval::{Trajectory, associate, metrics};
//!
//! let gt: Vec<_> = (0..5).map(|i| Isometry3::translation(0.0, 0.0, i as f64)).collect();
//! let est: Vec<_> = (0..5).map(|i| Isometry3::translation(0.0, 0.0, 1.1 * i as f64)).collect();
//! let pairs = associate::by_index(&Trajectory::indexed("est", est), &Trajectory::indexed("gt", gt))?;
//! let e = metrics::evaluate(&pairs)?;
//! assert!((e.final_drift_percent.unwrap() - 10.0).abs() < 1e-9);
//! # Ok::<(), swarmpose_eval::EvalError>(())
//! ```
#![deny(missing_docs)]
#![forbid(unsafe_code)]
#![warn(clippy::unwrap_used)]

pub mod associate;
pub mod error;
pub mod metrics;
pub mod segments;
pub mod trajectory;

pub use error::EvalError;
pub use metrics::{Evaluation, Stats, evaluate, evaluate_with};
pub use segments::{KittiSegments, kitti_segments};
pub use trajectory::{Format, Trajectory};
