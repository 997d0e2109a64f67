//! `pso` on the stereo-noise generator: units and scene size do not matter, a wrong pose
//! is never a plain success, and a single motion is not flagged ambiguous.
#![allow(clippy::unwrap_used)]

use swarmpose_core::{Correspondences, Estimator, PsoEstimator};
use swarmpose_sim::{StereoScenario, StereoSpec};

/// (right, wrong plain successes, errors) of the default `pso` over `seeds`.
fn tally(
    spec: &StereoSpec,
    seeds: std::ops::Range<u64>,
    data: impl Fn(&StereoScenario) -> Correspondences,
) -> (usize, usize, usize) {
    let (mut right, mut wrong, mut errors) = (0, 0, 0);
    for seed in seeds {
        let s = spec.scenario(5000 + seed).unwrap();
        match PsoEstimator::default().estimate_seeded(&data(&s), seed) {
            Ok(e) if s.is_success(&e.transform) => right += 1,
            Ok(_) => wrong += 1,
            Err(_) => errors += 1,
        }
    }
    (right, wrong, errors)
}

#[test]
fn tabletop_and_millimetres_at_90_percent_outliers() {
    for (name, spec) in [
        ("tabletop", StereoSpec::tabletop()),
        ("street in mm", StereoSpec::street().with_unit(1000.0)),
        ("tabletop in mm", StereoSpec::tabletop().with_unit(1000.0)),
    ] {
        let spec = spec.with_outliers(0.9);
        let (right, wrong, errors) = tally(&spec, 0..100, |s| s.data.clone());
        println!("{name}, covariances: {right}/100 right, {wrong} wrong, {errors} errors");
        assert!(right >= 95, "{name}: {right}/100");
        assert_eq!(wrong, 0, "{name}: wrong poses returned as successes");
    }
}

#[test]
fn without_covariances_the_range_noise_model_recovers_the_precision() {
    // Plain coordinates: the residuals choose the noise model that grows with the range
    // along the viewing ray, so the fit is as precise as with the covariances; a pose
    // that misses the bars is never a plain success.
    for f in [0.9, 0.95, 0.97] {
        let spec = StereoSpec::tabletop().with_unit(1000.0).with_outliers(f);
        let (right, wrong, errors) = tally(&spec, 0..40, |s| s.plain().unwrap());
        let (with, _, _) = tally(&spec, 0..40, |s| s.data.clone());
        println!(
            "{f}: plain {right}/40 right, {wrong} wrong, {errors} errors; covariances {with}/40"
        );
        assert_eq!(wrong, 0, "{f}: a wrong pose returned as a success");
        // Within one run per 20 of the estimate with the true covariances.
        assert!(
            right + 2 >= with,
            "{f}: plain {right}/40, covariances {with}/40"
        );
    }
}

#[test]
fn a_single_motion_is_not_ambiguous() {
    let mut flagged = 0;
    for seed in 0..100u64 {
        let f = [0.5, 0.6, 0.7, 0.8, 0.9][(seed % 5) as usize];
        let s = StereoSpec::street()
            .with_outliers(f)
            .scenario(9000 + seed)
            .unwrap();
        for data in [s.data.clone(), s.plain().unwrap()] {
            if let Ok(e) = PsoEstimator::default().estimate_seeded(&data, seed) {
                flagged += usize::from(e.is_ambiguous());
            }
        }
    }
    println!("ambiguous: {flagged} of 200 single-motion estimates");
    assert!(flagged <= 4, "{flagged} of 200 flagged ambiguous");
}
