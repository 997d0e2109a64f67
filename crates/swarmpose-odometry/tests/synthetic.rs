//! The built-in synthetic sequence: the default run follows the known path to within
//! 0.1 % of its length, and the exact rig gets no correction.

mod common;

use swarmpose_datasets::StereoSequence;
use swarmpose_odometry::synthetic::SyntheticSequence;
use swarmpose_odometry::{CorrectionModel, OdometryConfig};

#[test]
fn synthetic_sequence_is_followed() {
    let seq = SyntheticSequence::default();
    let r = common::run_sequence(&seq, OdometryConfig::default());
    let e = common::evaluate_poses(r.poses(), seq.ground_truth().expect("known path"));
    for f in &r.results {
        eprintln!(
            "frame {:2}: {:4} stereo {:4} matches {:4} inliers {}",
            f.index,
            f.counts.stereo_points,
            f.counts.matches,
            f.counts.inliers,
            f.status.text()
        );
    }
    let drift = e.final_drift_percent.expect("11 m");
    eprintln!(
        "synthetic: correction {}, path {:.2} m, drift {:.4} m ({drift:.3} %), RMS eq. (20) {:.5}, ATE {:.4} m",
        r.calibration.correction, e.path_length_m, e.final_drift_m, e.eq20_rms, e.ate_aligned.rmse
    );
    assert_eq!(r.untracked(), 0);
    assert_eq!(r.calibration.model, CorrectionModel::NONE);
    assert!(drift <= 0.1, "drift {drift:.3} %");
    assert!(e.eq20_rms < 0.001);
}
