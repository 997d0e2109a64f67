//! `pso` on the stereo-noise generator: units and scene size do not matter, a wrong pose
//! is never a plain success, and a single motion is not flagged ambiguous.
#![allow(clippy::unwrap_used)]

use swarmpose_core::geometry::rotation_angle_between;
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
fn without_covariances_no_wrong_motion_is_a_plain_success() {
    // Without a noise model a fit to stereo points is less precise (some right
    // consensuses miss the 0.2 m bar); a pose 5 degrees or 5 bars off is a wrong motion.
    for f in [0.9, 0.95] {
        let spec = StereoSpec::tabletop().with_unit(1000.0).with_outliers(f);
        let (mut right, mut gross) = (0, 0);
        for seed in 0..40 {
            let s = spec.scenario(7000 + seed).unwrap();
            if let Ok(e) = PsoEstimator::default().estimate_seeded(&s.plain().unwrap(), seed) {
                let r = rotation_angle_between(&e.transform.rotation, &s.truth.rotation);
                let t = (e.transform.translation.vector - s.truth.translation.vector).norm();
                right += usize::from(s.is_success(&e.transform));
                gross += usize::from(r.to_degrees() > 5.0 || t > 5.0 * s.success_translation);
            }
        }
        println!("{f}: plain {right}/40 right, {gross} wrong motions");
        assert_eq!(gross, 0, "{f}: a wrong motion returned as a success");
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
