//! The built-in synthetic sequence: the default run follows the known path.

use swarmpose_core::{PsoEstimator, PsoEstimatorConfig};
use swarmpose_datasets::StereoSequence;
use swarmpose_eval::associate::by_index;
use swarmpose_eval::{Trajectory, evaluate};
use swarmpose_odometry::synthetic::SyntheticSequence;
use swarmpose_odometry::{OdometryConfig, run};
use swarmpose_vision::frontend::Frontend;

#[test]
fn synthetic_sequence_is_followed() {
    let seq = SyntheticSequence::default();
    let frontend = Frontend::orb(seq.calibration());
    let estimator = PsoEstimator::new(PsoEstimatorConfig::default());
    let t = std::time::Instant::now();
    let r = run(
        &seq,
        &frontend,
        &estimator,
        &OdometryConfig::default(),
        &mut |_, _| {},
    )
    .expect("odometry");
    let gt = seq.ground_truth().expect("known path").to_vec();
    let pairs = by_index(
        &Trajectory::indexed("estimate", r.poses.clone()),
        &Trajectory::indexed("truth", gt),
    )
    .expect("pairs");
    let e = evaluate(&pairs).expect("evaluate");
    for f in &r.frames {
        eprintln!(
            "frame {:2}: {:4} stereo {:4} matches {:4} inliers {}",
            f.frame,
            f.n_stereo,
            f.n_matches,
            f.n_inliers,
            f.status.text()
        );
    }
    eprintln!(
        "synthetic: {:.1} s, disparity correction {}, path {:.2} m, drift {:.3} m ({:.2} %), RMS eq. (20) {:.5}, ATE {:.3} m",
        t.elapsed().as_secs_f64(),
        r.disparity_correction,
        e.path_length_m,
        e.final_drift_m,
        e.final_drift_percent.unwrap_or(f64::NAN),
        e.eq20_rms,
        e.ate_aligned.rmse
    );
    assert_eq!(r.n_fallbacks(), 0);
    // The renderer's stereo is exact: the self-calibration must find (almost) nothing.
    let c = r.disparity_correction;
    assert!(
        c.offset_px.abs() < 0.1 && c.quadratic_px.abs() < 0.5,
        "self-calibrated {c} on an exact rig"
    );
    assert!(e.final_drift_percent.expect("11 m") < 0.5);
    assert!(e.eq20_rms < 0.01);
}
