//! TUM RGB-D input on frames of the synthetic street rendered with exact depth: the
//! trajectory follows the known path, and malformed directories give clear errors.

use swarmpose_core::{PsoEstimator, PsoEstimatorConfig};
use swarmpose_eval::associate::by_index;
use swarmpose_eval::{Trajectory, evaluate};
use swarmpose_odometry::OdometryConfig;
use swarmpose_odometry::rgbd::{RgbdSequence, run_rgbd};
use swarmpose_odometry::synthetic::{RIG, SyntheticSequence};
use swarmpose_vision::frontend::Frontend;

fn tmp(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("swarmpose-rgbd-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp");
    d
}

#[test]
fn synthetic_tum_rgbd_is_followed() {
    let dir = tmp("ok");
    // 12 frames, 0.3 m and 1 degree per frame.
    SyntheticSequence::new(12, 0.3, 1f64.to_radians())
        .write_tum_rgbd(&dir)
        .expect("write");
    let seq = RgbdSequence::open(&dir).expect("open");
    assert_eq!(seq.len(), 12);
    let frontend = Frontend::orb(RIG);
    let estimator = PsoEstimator::new(PsoEstimatorConfig::default());
    let r = run_rgbd(
        &seq,
        &frontend,
        &estimator,
        &OdometryConfig::default(),
        &mut |_, _| {},
    )
    .expect("run");
    let gt = seq.ground_truth().expect("groundtruth.txt").to_vec();
    // Re-based on the first frame: the first true pose is the identity.
    assert!(gt[0].translation.vector.norm() < 1e-9);
    let e = evaluate(
        &by_index(
            &Trajectory::indexed("estimate", r.poses.clone()),
            &Trajectory::indexed("truth", gt),
        )
        .expect("pairs"),
    )
    .expect("evaluate");
    for f in &r.frames {
        eprintln!(
            "frame {:2}: {:4} points {:4} matches {:4} inliers {}",
            f.frame,
            f.n_stereo,
            f.n_matches,
            f.n_inliers,
            f.status.text()
        );
    }
    eprintln!(
        "rgbd: path {:.2} m, drift {:.4} m ({:.2} %), RMS eq. (20) {:.5}, ATE {:.4} m",
        e.path_length_m,
        e.final_drift_m,
        e.final_drift_percent.unwrap_or(f64::NAN),
        e.eq20_rms,
        e.ate_aligned.rmse
    );
    assert!((r.stamps[1] - r.stamps[0] - 1.0 / 30.0).abs() < 1e-5);
    assert_eq!(r.n_fallbacks(), 0);
    assert!(e.final_drift_percent.expect("3.3 m") < 2.0);
    assert!(e.eq20_rms < 0.01);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malformed_tum_rgbd_gives_clear_errors() {
    let dir = tmp("bad");
    std::fs::write(dir.join("rgb.txt"), "# c\n1.0 rgb/1.png\n2.0\n").expect("w");
    std::fs::write(dir.join("depth.txt"), "1.0 depth/1.png\n").expect("w");
    let e = RgbdSequence::open(&dir)
        .expect_err("truncated line")
        .to_string();
    assert!(
        e.contains("rgb.txt:3") && e.contains("timestamp filename"),
        "{e}"
    );
    std::fs::write(dir.join("rgb.txt"), "1.0 rgb/1.png\n2.0 rgb/2.png\n").expect("w");
    let e = RgbdSequence::open(&dir)
        .expect_err("no depth for 2.0")
        .to_string();
    assert!(
        e.contains("depth.txt") && e.contains("colour image 2"),
        "{e}"
    );
    std::fs::write(dir.join("depth.txt"), "1.0 depth/1.png\n2.01 depth/2.png\n").expect("w");
    std::fs::write(dir.join("groundtruth.txt"), "1.0 0 0 0 0 0 0 1\n").expect("w");
    let e = RgbdSequence::open(&dir).expect_err("gt short").to_string();
    assert!(
        e.contains("groundtruth.txt") && e.contains("frame 2"),
        "{e}"
    );
    std::fs::write(dir.join("groundtruth.txt"), "1.0 0 0 0 0 0 1\n").expect("w");
    let e = RgbdSequence::open(&dir)
        .expect_err("gt truncated")
        .to_string();
    assert!(
        e.contains("groundtruth.txt:1") && e.contains("8 numbers"),
        "{e}"
    );
    std::fs::remove_file(dir.join("groundtruth.txt")).expect("rm");
    let seq = RgbdSequence::open(&dir).expect("no ground truth is fine");
    let e = seq.frame(0).expect_err("missing png").to_string();
    assert!(e.contains("1.png"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
