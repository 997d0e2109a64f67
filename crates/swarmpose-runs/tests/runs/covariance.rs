//! The motion covariance on real images, checked without ground truth: each tracked
//! pair's motion is refined again on the left and on the right half of its inliers
//! ([`swarmpose_odometry::refine::split`]), and the mean normalised squared difference of
//! the two (6 when the covariance is honest) must lie in the issue's [3, 12]. Each pair is
//! judged with the systematic floor ([`swarmpose_odometry::refine::floor`], on by default)
//! learned from the pairs before it only: a held-out check of the floor, not a fit to the
//! pairs it judges. Without the floor the model alone gives far more on KITTI and
//! Karlsruhe (errors shared by a half of the image; RESULTS.md, "Covariance").

use std::ops::ControlFlow;

use swarmpose_datasets::open;
use swarmpose_odometry::{Odometry, OdometryConfig};
use swarmpose_runs::batch::{camera_of, run_sequence};

/// The split-feature NEES (with the floor, and the model's alone) of the first `frames`
/// frames of a shared sequence, frame to frame, or `None` when the data is absent.
fn split_nees(name: &str, frames: usize) -> Option<Vec<(f64, f64)>> {
    let dir = crate::common::dataset(name)?;
    let seq = open(&dir).expect("open");
    let config = OdometryConfig {
        split_check: true,
        ..OdometryConfig::default()
    }
    .with_window(0);
    let mut odo = Odometry::new(camera_of(seq.as_ref()), config).expect("engine");
    let mut nees = Vec::new();
    let mut seen = 0;
    run_sequence(seq.as_ref(), &mut odo, 0.1, &mut |r| {
        nees.extend(r.split.map(|s| (s.nees, s.model_nees)));
        seen += 1;
        if seen >= frames {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })
    .expect("odometry");
    Some(nees)
}

fn check(name: &str, frames: usize, bounds: std::ops::RangeInclusive<f64>) {
    let Some(nees) = split_nees(name, frames) else {
        return;
    };
    let n = nees.len() as f64;
    let mean = nees.iter().map(|x| x.0).sum::<f64>() / n;
    let model = nees.iter().map(|x| x.1).sum::<f64>() / n;
    eprintln!(
        "{name}: split-feature mean NEES {mean:.2} with the floor, {model:.2} the model's \
         alone, over {} pairs",
        nees.len()
    );
    assert!(nees.len() * 2 >= frames, "{} pairs checked", nees.len());
    // The first pair has no past: the floor adds nothing to it.
    assert_eq!(nees[0].0, nees[0].1, "the first pair's floor");
    assert!(bounds.contains(&mean), "{name}: mean NEES {mean:.2}");
}

/// The still EuRoC clip (30 frames): within the issue's [3, 12] (6.21 measured; 6.75
/// the model's covariance alone).
#[test]
fn euroc_split_feature_nees() {
    check("euroc_v1_01_easy_micro", 30, 3.0..=12.0);
}

/// kitti_vo_seq2, its first 30 frames: within the issue's [3, 12] (6.95 measured; the
/// model's covariance alone: 28.2 here, 30.5 over the 51 frames).
#[test]
fn kitti_split_feature_nees() {
    check("kitti_vo_seq2", 30, 3.0..=12.0);
}

/// Karlsruhe, its first 30 frames: within the issue's [3, 12] (5.93 measured; the
/// model's covariance alone: 18.5 here, 90.7 over the whole sequence).
#[test]
fn karlsruhe_split_feature_nees() {
    check("karlsruhe_2010_03_09_drive_0023", 30, 3.0..=12.0);
}

/// A synthetic feature stream with independent pixel noise of known size (0.5 px, as
/// `tests/runs/streaming.rs`): the split-feature NEES is within [4.5, 7.5] over 80 pairs (6.30
/// over 150 pairs measured, 5.58 at 1 px; the mean of 80 has a standard deviation of
/// about 0.4).
#[test]
fn synthetic_split_feature_nees() {
    use swarmpose_runs::synthetic::features::{FeatureSequence, FeatureSequenceConfig};
    let mut config = FeatureSequenceConfig {
        seed: 11,
        ..FeatureSequenceConfig::default()
    };
    config.noise.position_px = 0.5;
    config.noise.disparity_px = 0.25;
    let seq = FeatureSequence::new(config);
    let mut tracker = seq.tracker(
        OdometryConfig {
            split_check: true,
            ..OdometryConfig::default()
        }
        .with_window(0),
    );
    let mut nees = Vec::new();
    crate::common::stream(&seq, &mut tracker, 81, |_, r| {
        nees.extend(r.split.map(|s| s.nees));
    });
    let mean = nees.iter().sum::<f64>() / nees.len() as f64;
    eprintln!(
        "synthetic 0.5 px: split-feature mean NEES {mean:.2} over {} pairs",
        nees.len()
    );
    assert!(nees.len() >= 75, "{} pairs checked", nees.len());
    assert!((4.5..=7.5).contains(&mean), "mean NEES {mean:.2}");
}

/// The rendered synthetic street (the built-in sequence of `swarmpose odometry` with no
/// path: 20 frames, 0.6 m and 1 degree a frame), over its first five draws of the textures
/// (seed 0 is the built-in one): the pooled split-feature NEES, held out as the engine
/// gives it, is within the issue's [4.5, 7.5]. One street has only 19 pairs, whose mean
/// has a standard deviation of about 0.8 (0.76 measured over 40 textures, around a mean
/// of 6.83: `tools/covariance/street.py`, RESULTS.md "Covariance: the rendered street"),
/// so one street alone is not a test of the bar; five give 95 pairs (about 0.34).
#[test]
#[ignore = "slow: .ci/run runs it (cargo test --workspace --test runs -- --ignored)"]
fn street_split_feature_nees() {
    use swarmpose_runs::synthetic::SyntheticSequence;
    let (mut nees, mut model) = (Vec::new(), Vec::new());
    for seed in 0..5 {
        let seq = SyntheticSequence::new(20, 0.6, 1f64.to_radians()).with_texture_seed(seed);
        let config = OdometryConfig {
            split_check: true,
            ..OdometryConfig::default()
        }
        .with_window(0);
        let mut odo = Odometry::new(camera_of(&seq), config).expect("engine");
        run_sequence(&seq, &mut odo, 0.1, &mut |r| {
            if let Some(s) = r.split {
                nees.push(s.nees);
                model.push(s.model_nees);
            }
            ControlFlow::Continue(())
        })
        .expect("odometry");
    }
    let mean = |x: &[f64]| x.iter().sum::<f64>() / x.len() as f64;
    eprintln!(
        "street, 5 textures: split-feature mean NEES {:.2} with the floor, {:.2} the \
         model's alone, over {} pairs",
        mean(&nees),
        mean(&model),
        nees.len()
    );
    assert!(nees.len() >= 90, "{} pairs checked", nees.len());
    assert!(
        (4.5..=7.5).contains(&mean(&nees)),
        "mean NEES {:.2}",
        mean(&nees)
    );
}
