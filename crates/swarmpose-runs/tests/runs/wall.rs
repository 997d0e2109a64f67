//! Self-calibration where it is not identifiable: an exact rig facing one flat textured
//! wall. Every point is at the same depth in a frame, so a disparity offset and a scale of
//! the scene are nearly the same thing (`selfcal::scene`); no correction may be applied,
//! the path must be exact, and the decision must say that rigidity could not observe the
//! calibration. Before the plane check, the engine applied an offset larger than the true
//! disparity here and the path came out about a third short (issue 29).

use nalgebra::Isometry3;
use swarmpose_datasets::StereoSequence;
use swarmpose_odometry::{CorrectionModel, OdometryConfig};
use swarmpose_runs::synthetic::SyntheticSequence;

fn path_length_m(poses: &[Isometry3<f64>]) -> f64 {
    poses
        .windows(2)
        .map(|w| (w[1].translation.vector - w[0].translation.vector).norm())
        .sum()
}

/// A wall at several distances, approached, left and passed obliquely.
#[test]
fn exact_rig_facing_a_wall_gets_no_correction_and_the_exact_path() {
    for (distance_m, step_m) in [
        (10.0, [0.0, 0.0, 0.3]),
        (20.0, [0.0, 0.0, -0.6]),
        (6.0, [0.15, 0.0, 0.15]),
    ] {
        let seq = SyntheticSequence::facing_wall(8, distance_m, step_m, 0.005 * distance_m);
        let run = crate::common::run_sequence(&seq, OdometryConfig::default());
        let ratio =
            path_length_m(&run.poses()) / path_length_m(seq.ground_truth().expect("a known path"));
        let d = &run.calibration;
        eprintln!(
            "wall {distance_m} m, step {step_m:?} m: {} {}, {} pairs with evidence, {} on one \
             plane; path ratio {ratio:.4}",
            d.model, d.correction, d.pairs, d.one_plane_pairs
        );
        assert_eq!(run.untracked(), 0);
        for r in &run.results {
            let c = r.correction;
            assert!(
                c.offset_px == 0.0 && c.linear_x_px == 0.0 && r.focal_px == 0.0,
                "wall {distance_m} m, frame {}: {} {c}",
                r.index,
                r.correction_model
            );
        }
        assert_eq!(d.model, CorrectionModel::NONE);
        assert!(d.rigidity_unobservable(), "{d:?}");
        assert!((ratio - 1.0).abs() <= 0.01, "path ratio {ratio:.4}");
    }
}
