//! Synthetic-recovery tests of every estimator.

use nalgebra::{Isometry3, Point3, Vector3};

use super::*;
use crate::geometry::rotation_angle_between;
use crate::synthetic::{SyntheticScenario, SyntheticSpec};

fn all_estimators() -> Vec<Box<dyn Estimator>> {
    vec![
        Box::new(PsoEstimator::default()),
        Box::new(PsoPaperEstimator::default()),
        Box::new(SvdEstimator),
        Box::new(MsacEstimator::default()),
    ]
}

fn errors(est: &Isometry3<f64>, truth: &Isometry3<f64>) -> (f64, f64) {
    (
        rotation_angle_between(&est.rotation, &truth.rotation).to_degrees(),
        (est.translation.vector - truth.translation.vector).norm(),
    )
}

fn scenario(noise: f64, outliers: f64, seed: u64) -> SyntheticScenario {
    SyntheticSpec {
        noise_sigma_m: noise,
        outlier_fraction: outliers,
        ..SyntheticSpec::default()
    }
    .generate(seed)
    .expect("valid spec")
}

#[test]
fn every_estimator_is_exact_on_clean_data() {
    // (With a δ much tighter than the scene, e.g. 0.01 m, pso-paper fails 3-7 % of clean
    // runs: a point near the centroid "supports" any rotation, and the support-first
    // choice of eq. (15) then prefers a wrong particle. See the notes.)
    for seed in 0..20 {
        let s = scenario(0.0, 0.0, seed);
        for e in all_estimators() {
            let out = e
                .estimate_seeded(&s.data, seed)
                .unwrap_or_else(|err| panic!("{} seed {seed}: {err}", e.name()));
            let (rot_deg, trans_m) = errors(&out.transform, &s.truth);
            assert!(
                rot_deg < 1e-7 && trans_m < 1e-9,
                "{}: {rot_deg} deg {trans_m} m",
                e.name()
            );
            assert_eq!(out.inliers.len(), s.data.len(), "{}", e.name());
        }
    }
}

#[test]
fn robust_estimators_recover_with_half_outliers() {
    for e in [
        &PsoEstimator::default() as &dyn Estimator,
        &MsacEstimator::default(),
    ] {
        let mut ok = 0;
        for seed in 0..20 {
            let s = scenario(0.02, 0.5, 100 + seed);
            if let Ok(out) = e.estimate_seeded(&s.data, seed) {
                let (rot_deg, trans_m) = errors(&out.transform, &s.truth);
                let correct = out.inliers.iter().filter(|&&i| s.inlier[i]).count();
                if rot_deg < 0.5 && trans_m < 0.1 && correct * 10 >= out.inliers.len() * 9 {
                    ok += 1;
                }
            }
        }
        assert!(ok >= 19, "{}: {ok}/20", e.name());
    }
}

#[test]
fn svd_is_biased_by_one_wrong_match() {
    let mut s = scenario(0.0, 0.0, 3);
    let mut dst = s.data.dst().to_vec();
    dst[0] = Point3::new(50.0, 50.0, 50.0);
    s.data = crate::Correspondences::new(s.data.src().to_vec(), dst).expect("finite");
    let out = SvdEstimator.estimate_seeded(&s.data, 0).expect("solvable");
    let (_, trans_m) = errors(&out.transform, &s.truth);
    assert!(trans_m > 0.1, "one outlier moved SVD by only {trans_m} m");
    let robust = PsoEstimator::default()
        .estimate_seeded(&s.data, 0)
        .expect("solvable");
    assert!(!robust.inliers.contains(&0));
}

#[test]
fn same_seed_same_result() {
    let s = scenario(0.02, 0.3, 11);
    for e in all_estimators() {
        let a = e.estimate_seeded(&s.data, 5);
        let b = e.estimate_seeded(&s.data, 5);
        match (a, b) {
            (Ok(a), Ok(b)) => {
                assert_eq!(a.transform, b.transform, "{}", e.name());
                assert_eq!(a.inliers, b.inliers, "{}", e.name());
            }
            (Err(a), Err(b)) => assert_eq!(a, b),
            _ => panic!("{}: one run failed, the other did not", e.name()),
        }
    }
}

#[test]
fn bad_input_is_a_typed_error() {
    let p = Point3::new(1.0, 2.0, 3.0);
    let three = crate::Correspondences::new(vec![p; 3], vec![p; 3]).expect("finite");
    let same = crate::Correspondences::new(vec![p; 10], vec![p; 10]).expect("finite");
    let line: Vec<_> = (0..10)
        .map(|i| p + Vector3::new(i as f64, 0.5 * i as f64, 0.0))
        .collect();
    let collinear = crate::Correspondences::new(line.clone(), line).expect("finite");
    for e in all_estimators() {
        assert!(matches!(
            e.estimate_seeded(&three, 0),
            Err(PoseError::TooFewPoints { got: 3, needed: 4 })
        ));
        assert!(matches!(
            e.estimate_seeded(&same, 0),
            Err(PoseError::Degenerate {
                kind: crate::DegeneracyKind::Coincident,
                ..
            })
        ));
        assert!(matches!(
            e.estimate_seeded(&collinear, 0),
            Err(PoseError::Degenerate {
                kind: crate::DegeneracyKind::Collinear,
                ..
            })
        ));
    }
}

#[test]
fn pure_garbage_is_insufficient_support_not_a_pose() {
    // Every match wrong: no rigid motion has support.
    let s = scenario(0.02, 1.0, 21);
    for e in [
        &PsoEstimator::default() as &dyn Estimator,
        &MsacEstimator::default(),
    ] {
        match e.estimate_seeded(&s.data, 1) {
            Err(PoseError::InsufficientSupport { .. }) => {}
            Ok(out) => assert!(
                out.inliers.len() < 12,
                "{} claims {} inliers in pure noise",
                e.name(),
                out.inliers.len()
            ),
            Err(other) => panic!("{}: unexpected {other}", e.name()),
        }
    }
}

#[test]
fn invalid_thresholds_are_rejected() {
    let s = scenario(0.0, 0.0, 1);
    for thr in [0.0, -1.0, f64::NAN, f64::INFINITY] {
        assert!(
            PsoEstimator::new(PsoEstimatorConfig::default().with_threshold(thr))
                .estimate_seeded(&s.data, 0)
                .is_err()
        );
        assert!(
            MsacEstimator::new(MsacConfig::default().with_threshold(thr))
                .estimate_seeded(&s.data, 0)
                .is_err()
        );
        assert!(
            PsoPaperEstimator::new(PsoPaperConfig::default().with_threshold(thr))
                .estimate_seeded(&s.data, 0)
                .is_err()
        );
    }
}

/// The literal method's weakness, measured: outliers move the all-point centroids of
/// eq. (7)-(8), so at the true rotation the centred residuals of the inliers are offset by
/// `b = p̄' - R p̄ - t` and few or none pass δ. Success falls as outliers are added.
#[test]
fn pso_paper_degrades_with_outliers_as_recorded() {
    let delta = 0.07; // 3.4 σ for σ = 0.02 m
    let est = PsoPaperEstimator::new(PsoPaperConfig::default().with_threshold(delta));
    let runs = 20;
    let mut table = Vec::new();
    for frac in [0.0, 0.1, 0.3, 0.5] {
        let (mut bias_sum, mut passing_sum, mut ok) = (0.0, 0usize, 0usize);
        for run in 0..runs {
            let s = scenario(0.02, frac, 500 + run);
            let n = s.data.len() as f64;
            let cs = s.data.src().iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
            let cd = s.data.dst().iter().map(|p| p.coords).sum::<Vector3<f64>>() / n;
            let r = s.truth.rotation;
            bias_sum += (cd - r * cs - s.truth.translation.vector).norm();
            passing_sum += (0..s.data.len())
                .filter(|&i| {
                    s.inlier[i]
                        && ((s.data.dst()[i].coords - cd) - r * (s.data.src()[i].coords - cs))
                            .norm()
                            < delta
                })
                .count();
            if let Ok(out) = est.estimate_seeded(&s.data, run) {
                let (rot_deg, trans_m) = errors(&out.transform, &s.truth);
                ok += usize::from(rot_deg < 0.5 && trans_m < 0.1);
            }
        }
        let row = (
            frac,
            bias_sum / runs as f64,
            passing_sum as f64 / runs as f64,
            ok,
        );
        eprintln!(
            "pso-paper: outliers {:.1}: centroid bias {:.2} m, inliers within δ at the true rotation {:.1} of 200, success {}/{runs}",
            row.0, row.1, row.2, row.3
        );
        table.push(row);
    }
    // Clean data: unbiased, every inlier passes, always solved.
    assert!(table[0].1 < 0.01 && table[0].2 > 195.0 && table[0].3 == runs as usize);
    // 10 % wrong matches: the centroids are ~0.25 m off here (0.5 m with the shared
    // generator's visibility test) and no inlier passes δ at the truth.
    assert!(table[1].1 > 0.15, "bias at 10 %: {}", table[1].1);
    assert!(table[1].2 < 1.0, "inliers passing at 10 %: {}", table[1].2);
    // The swarm converges on the biased least-squares rotation: measured 1/20 at 10 %,
    // 0/20 at 30 % and 50 %, while the bias keeps growing.
    assert!(table[2].1 > 0.3 && table[3].1 > table[2].1);
    assert!(table[1].3 <= 4 && table[2].3 <= 2 && table[3].3 <= 2);
    // The robust variant solves the same scenarios.
    for run in 0..runs {
        let s = scenario(0.02, 0.5, 500 + run);
        let out = PsoEstimator::new(PsoEstimatorConfig::default().with_threshold(delta))
            .estimate_seeded(&s.data, run)
            .expect("pso solves 50 % outliers");
        let (rot_deg, trans_m) = errors(&out.transform, &s.truth);
        assert!(rot_deg < 0.5 && trans_m < 0.1);
    }
}

#[test]
fn pso_handles_large_sets_through_sampled_pairs() {
    // 3000 points: more pairs than the budget, so pairs are drawn at random.
    for (seed, outliers) in [(1u64, 0.0), (2, 0.5), (3, 0.9)] {
        let s = SyntheticSpec {
            n: 3000,
            outlier_fraction: outliers,
            ..SyntheticSpec::default()
        }
        .generate(seed)
        .expect("valid spec");
        let out = PsoEstimator::new(PsoEstimatorConfig::default().with_threshold(0.07))
            .estimate_seeded(&s.data, seed)
            .expect("solvable");
        let (rot_deg, trans_m) = errors(&out.transform, &s.truth);
        assert!(
            rot_deg < 0.5 && trans_m < 0.1,
            "{outliers}: {rot_deg} deg {trans_m} m"
        );
        let truly = out.inliers.iter().filter(|&&i| s.inlier[i]).count();
        assert!(truly * 100 >= out.inliers.len() * 95);
    }
}

#[test]
fn pso_solves_small_objects_on_clean_data() {
    // Every point within ~0.3 m, default δ = 0.1 m: pairs are shorter than 5δ.
    let spec = SyntheticSpec {
        n: 20,
        noise_sigma_m: 0.0,
        box_lo: [-0.15, -0.15, 1.0],
        box_hi: [0.15, 0.15, 1.3],
        ..SyntheticSpec::default()
    };
    for seed in 0..8 {
        let s = spec.generate(seed).expect("valid spec");
        let out = PsoEstimator::default()
            .estimate_seeded(&s.data, seed)
            .expect("solvable");
        let (rot_deg, trans_m) = errors(&out.transform, &s.truth);
        assert!(
            rot_deg < 1e-6 && trans_m < 1e-9,
            "seed {seed}: {rot_deg} deg {trans_m} m"
        );
    }
}
