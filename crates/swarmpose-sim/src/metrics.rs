//! What one estimation is judged by: pose errors against the truth, success, inlier
//! precision and recall, time.

use std::time::Duration;

use swarmpose_core::geometry::{frobenius_rotation_error, rotation_angle_between};
use swarmpose_core::{Estimate, PoseError};

use crate::outliers::Scenario;

/// Largest rotation error of a success, degrees (as the peers).
pub const SUCCESS_ROTATION_DEG: f64 = 2.0;
/// Largest position error of a success, metres (as the peers).
pub const SUCCESS_POSITION_M: f64 = 0.2;

/// One row of `runs.csv`: one estimator on one scenario. Values that need a pose are NaN
/// when the estimator returned none (`error` says why).
#[derive(Debug, Clone, PartialEq)]
pub struct RunRecord {
    /// Noise σ, metres.
    pub noise_sigma: f64,
    /// Requested outlier fraction.
    pub outlier_fraction: f64,
    /// Run index (0-based).
    pub run: usize,
    /// Run seed (geometry).
    pub seed: u64,
    /// Estimator name.
    pub estimator: String,
    /// Inlier threshold given to the estimator, metres.
    pub threshold_m: f64,
    /// Correspondences.
    pub n: usize,
    /// True outliers.
    pub n_outliers: usize,
    /// `|t_est - t_true|`, metres.
    pub position_error_m: f64,
    /// Angle of `R_est^T R_true`, degrees.
    pub rotation_error_deg: f64,
    /// The paper's eq. (20), `||I - R_true R_est^T||_F`.
    pub rotation_error_frobenius: f64,
    /// Rotation error below [`SUCCESS_ROTATION_DEG`] and position error below
    /// [`SUCCESS_POSITION_M`].
    pub success: bool,
    /// Inliers returned.
    pub n_inliers_estimated: usize,
    /// Share of the returned inliers that are true inliers.
    pub inlier_precision: f64,
    /// Share of the true inliers that were returned.
    pub inlier_recall: f64,
    /// Wall time of the estimation, milliseconds.
    pub elapsed_ms: f64,
    /// Main-loop iterations (PSO iterations, MSAC samples).
    pub iterations: usize,
    /// The estimator's error when it returned no pose.
    pub error: Option<String>,
}

impl RunRecord {
    /// A record with no pose (its errors and inlier shares NaN, no success, no inliers, no
    /// iterations, no error) and empty context: the fields a judged record sets replace
    /// them (`RunRecord { run, ..RunRecord::without_pose() }`).
    pub(crate) fn without_pose() -> Self {
        Self {
            noise_sigma: f64::NAN,
            outlier_fraction: f64::NAN,
            run: 0,
            seed: 0,
            estimator: String::new(),
            threshold_m: f64::NAN,
            n: 0,
            n_outliers: 0,
            position_error_m: f64::NAN,
            rotation_error_deg: f64::NAN,
            rotation_error_frobenius: f64::NAN,
            success: false,
            n_inliers_estimated: 0,
            inlier_precision: f64::NAN,
            inlier_recall: f64::NAN,
            elapsed_ms: f64::NAN,
            iterations: 0,
            error: None,
        }
    }
}

/// Context of a record: the scenario's run, the estimator and its threshold.
#[derive(Debug, Clone, Copy)]
pub struct RunKey<'a> {
    /// Run index.
    pub run: usize,
    /// Estimator name.
    pub estimator: &'a str,
    /// Threshold, metres.
    pub threshold_m: f64,
}

/// Judges an estimation of `scenario`; `fallback_elapsed` is used when there is no
/// estimate to read the time from.
#[must_use]
pub fn evaluate(
    scenario: &Scenario,
    key: RunKey<'_>,
    result: &Result<Estimate, PoseError>,
    fallback_elapsed: Duration,
) -> RunRecord {
    let mut rec = RunRecord {
        noise_sigma: scenario.noise_sigma,
        outlier_fraction: scenario.outlier_fraction,
        run: key.run,
        seed: scenario.seed,
        estimator: key.estimator.to_owned(),
        threshold_m: key.threshold_m,
        n: scenario.data.len(),
        n_outliers: scenario.n_outliers(),
        elapsed_ms: fallback_elapsed.as_secs_f64() * 1e3,
        ..RunRecord::without_pose()
    };
    match result {
        Err(e) => rec.error = Some(e.to_string()),
        Ok(est) => {
            let truth = &scenario.truth;
            rec.position_error_m =
                (est.transform.translation.vector - truth.translation.vector).norm();
            rec.rotation_error_deg =
                rotation_angle_between(&truth.rotation, &est.transform.rotation).to_degrees();
            rec.rotation_error_frobenius =
                frobenius_rotation_error(&truth.rotation, &est.transform.rotation);
            rec.success = rec.rotation_error_deg < SUCCESS_ROTATION_DEG
                && rec.position_error_m < SUCCESS_POSITION_M;
            let true_in = scenario.inlier.iter().filter(|&&b| b).count();
            let hits = est
                .inliers
                .iter()
                .filter(|&&i| scenario.inlier.get(i).copied().unwrap_or(false))
                .count();
            rec.n_inliers_estimated = est.inliers.len();
            rec.inlier_precision = ratio(hits, est.inliers.len());
            rec.inlier_recall = ratio(hits, true_in);
            rec.elapsed_ms = est.diagnostics.elapsed.as_secs_f64() * 1e3;
            rec.iterations = est.diagnostics.iterations;
        }
    }
    rec
}

fn ratio(a: usize, b: usize) -> f64 {
    if b == 0 {
        f64::NAN
    } else {
        a as f64 / b as f64
    }
}
