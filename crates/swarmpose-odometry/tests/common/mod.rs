//! Shared helpers of the odometry tests.
#![allow(dead_code)]

use std::path::PathBuf;

use swarmpose_core::{PsoEstimator, PsoEstimatorConfig};
use swarmpose_datasets::open;
use swarmpose_eval::associate::by_index;
use swarmpose_eval::{Evaluation, Trajectory, evaluate};
use swarmpose_odometry::{OdometryConfig, OdometryRun, run};
use swarmpose_vision::frontend::Frontend;

/// The directory of a shared data set (see [`swarmpose_datasets::dataset_for_test`]).
pub fn dataset(name: &str) -> Option<PathBuf> {
    swarmpose_datasets::dataset_for_test(name)
}

/// The default run (ORB front end, robust PSO) on a data set.
pub fn default_run(name: &str) -> Option<OdometryRun> {
    let dir = dataset(name)?;
    let seq = open(&dir).expect("open");
    let frontend = Frontend::orb(seq.calibration());
    let estimator = PsoEstimator::new(PsoEstimatorConfig::default());
    let r = run(
        seq.as_ref(),
        &frontend,
        &estimator,
        &OdometryConfig::default(),
        &mut |_, _| {},
    )
    .expect("odometry");
    Some(r)
}

/// Evaluation of a run against the sequence's camera ground truth.
pub fn evaluate_run(name: &str, r: &OdometryRun) -> Evaluation {
    let dir = dataset(name).expect("present");
    let seq = open(&dir).expect("open");
    let gt = seq.ground_truth().expect("ground truth").to_vec();
    let pairs = by_index(
        &Trajectory::indexed("estimate", r.poses.clone()),
        &Trajectory::indexed("ground truth", gt),
    )
    .expect("same length");
    evaluate(&pairs).expect("evaluate")
}
