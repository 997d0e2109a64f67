//! A truck ahead that keeps the camera's speed and holds more matches than the static
//! world: the estimator's strongest motion is then "standing still". The engine must
//! not say so with confidence: it flags the frames as ambiguous and takes the motion
//! that agrees with the constant-velocity prediction.

use swarmpose_odometry::{FrameResult, OdometryConfig};
use swarmpose_runs::synthetic::features::{FeatureSequence, FeatureSequenceConfig};
use swarmpose_runs::synthetic::vehicle::Vehicle;

/// Runs `frames` frames of `seq` through a tracker with `config`, printing each result
/// under `label`.
fn run(
    seq: &FeatureSequence,
    config: OdometryConfig,
    frames: usize,
    label: &str,
) -> Vec<FrameResult> {
    let mut tracker = seq.tracker(config);
    let mut results = Vec::with_capacity(frames);
    crate::common::stream(seq, &mut tracker, frames, |_, r| {
        eprintln!(
            "{label}, frame {:2}: {:8} matches {:4} inliers {:4} ambiguous {} error {:.3} m",
            r.index,
            r.status.text(),
            r.counts.matches,
            r.counts.inliers,
            r.ambiguous,
            position_error_m(seq, r)
        );
        results.push(r.clone());
    });
    results
}

/// Distance between the estimated and the true position of frame `k`, metres.
fn position_error_m(seq: &FeatureSequence, r: &FrameResult) -> f64 {
    (r.pose.translation.vector - seq.pose(r.index).translation.vector).norm()
}

fn with_truck(features: usize, relative_step_m: f64) -> FeatureSequence {
    FeatureSequence::new(FeatureSequenceConfig {
        seed: 3,
        vehicle: Some(Vehicle {
            frames: (10, 30),
            features,
            distance_m: 9.0,
            relative_step_m,
        }),
        ..FeatureSequenceConfig::default()
    })
}

/// Runs 40 frames of `seq` frame to frame and with the window: every frame tracked, the
/// end within 0.5 % of the path, no frame flagged without the truck in both frames of
/// its pair; returns the frames flagged, per run.
fn flagged_frames(seq: &FeatureSequence, label: &str) -> Vec<Vec<FrameResult>> {
    [0, 10]
        .map(|keyframes| {
            let label = format!("{label}, window {keyframes}");
            let config = OdometryConfig::default().with_window(keyframes);
            let results = run(seq, config, 40, &label);
            for r in &results {
                assert!(r.status.is_tracked() || r.index == 0, "frame {}", r.index);
                // Frame 10 is matched to frame 9, where there is no truck yet.
                assert!(
                    !r.ambiguous || (11..=30).contains(&r.index),
                    "{label}, frame {}: no truck in both frames",
                    r.index
                );
            }
            let end = results.last().expect("frames");
            let drift = position_error_m(seq, end) / (39.0 * seq.config().step_m);
            assert!(
                drift < 0.005,
                "{label}: ends {:.1} % of the path off",
                100.0 * drift
            );
            results.into_iter().filter(|r| r.ambiguous).collect()
        })
        .to_vec()
}

/// The truck holds more matches than the static world (900 features on its back, about
/// 550 static ones): the estimator's strongest motion is "standing still". Frame to
/// frame and with the window, every frame with the truck in both images is flagged,
/// and the motion taken is the static world's, with fewer inliers than the truck's.
#[test]
fn a_truck_keeping_pace_is_flagged_and_not_followed() {
    let seq = with_truck(900, 0.0);
    for (run, flagged) in flagged_frames(&seq, "keeping pace").iter().enumerate() {
        assert!(
            flagged.len() >= 18,
            "run {run}: {} of the 20 frames with the truck in both are flagged",
            flagged.len()
        );
        for r in flagged {
            assert!(
                2 * r.counts.inliers < r.counts.matches,
                "run {run}, frame {}: {} inliers of {} matches",
                r.index,
                r.counts.inliers,
                r.counts.matches
            );
        }
    }
}

/// A truck that pulls away (0.3 m a frame faster than the camera) and one that holds
/// fewer features than the static world: the static world's motion is taken either way.
#[test]
fn other_trucks_do_not_take_the_pose() {
    flagged_frames(&with_truck(900, 0.3), "pulling away");
    for flagged in flagged_frames(&with_truck(250, 0.0), "small") {
        // The static world is the estimator's winner: a flag may say a second motion was
        // seen, but the motion taken holds most of the matches.
        for r in flagged {
            assert!(2 * r.counts.inliers > r.counts.matches, "frame {}", r.index);
        }
    }
}

/// The truck is there from the first frame: nothing predicts the motion, and the truck's
/// "standing still" is the strongest one. The engine cannot know which motion is the
/// camera's, but it must not say so with confidence: every frame with the truck in both
/// images is flagged (the leftover matches hold a second motion), and the flag ends with
/// the truck.
#[test]
fn a_truck_from_the_first_frame_is_flagged_throughout() {
    let seq = FeatureSequence::new(FeatureSequenceConfig {
        seed: 4,
        vehicle: Some(Vehicle {
            frames: (0, 20),
            features: 900,
            distance_m: 9.0,
            relative_step_m: 0.0,
        }),
        ..FeatureSequenceConfig::default()
    });
    for keyframes in [0, 10] {
        let label = format!("from the start, window {keyframes}");
        let results = run(
            &seq,
            OdometryConfig::default().with_window(keyframes),
            30,
            &label,
        );
        for r in &results {
            let both_seen = (1..=20).contains(&r.index);
            assert_eq!(
                r.ambiguous, both_seen,
                "window {keyframes}, frame {}: flagged {}",
                r.index, r.ambiguous
            );
        }
    }
}
