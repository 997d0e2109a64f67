//! Adversarial cases of `pso`: 95 % outliers, a moving object, depth-dependent noise,
//! very few inliers, the automatic threshold.

use nalgebra::{Isometry3, Point3, Vector3};
use rand::RngExt;
use rand_distr::{Distribution, Normal};

use super::*;
use crate::geometry::rotation_angle_between;
use crate::rng::seeded;
use crate::synthetic::SyntheticSpec;

fn errors(est: &Isometry3<f64>, truth: &Isometry3<f64>) -> (f64, f64) {
    (
        rotation_angle_between(&est.rotation, &truth.rotation).to_degrees(),
        (est.translation.vector - truth.translation.vector).norm(),
    )
}

#[test]
fn survives_95_percent_outliers() {
    let spec = SyntheticSpec {
        outlier_fraction: 0.95,
        ..SyntheticSpec::default()
    };
    let mut ok = 0;
    for seed in 0..20 {
        let s = spec.generate(700 + seed).expect("valid");
        if let Ok(out) = PsoEstimator::default().estimate_seeded(&s.data, seed) {
            let (r, t) = errors(&out.transform, &s.truth);
            ok += usize::from(r < 2.0 && t < 0.2);
        }
    }
    assert!(ok >= 19, "{ok}/20 at 95 % outliers");
}

#[test]
fn very_few_inliers_among_many() {
    // 8 correct matches among 400.
    let spec = SyntheticSpec {
        n: 400,
        outlier_fraction: 0.98,
        ..SyntheticSpec::default()
    };
    let s = spec.generate(5).expect("valid");
    let out = PsoEstimator::default()
        .estimate_seeded(&s.data, 1)
        .expect("solvable");
    let (r, t) = errors(&out.transform, &s.truth);
    assert!(r < 2.0 && t < 0.2, "{r} deg, {t} m");
    assert!(out.inliers.iter().filter(|&&i| s.inlier[i]).count() >= 6);
}

#[test]
fn auto_threshold_tracks_the_noise() {
    for sigma in [0.01, 0.05] {
        let spec = SyntheticSpec {
            noise_sigma_m: sigma,
            outlier_fraction: 0.5,
            ..SyntheticSpec::default()
        };
        let s = spec.generate(9).expect("valid");
        let out = PsoEstimator::default()
            .estimate_seeded(&s.data, 2)
            .expect("solvable");
        let d = out.diagnostics.threshold_m.expect("pso reports its δ");
        assert!(
            (d / (3.368 * sigma) - 1.0).abs() < 0.3,
            "σ {sigma}: δ {d} vs {}",
            3.368 * sigma
        );
        let (r, t) = errors(&out.transform, &s.truth);
        assert!(r < 0.5 && t < 0.1);
    }
}

/// Stereo-like noise: σ grows with the square of the depth, so one threshold either
/// rejects the far points or lets near outliers in. With σ_i attached, the far points are
/// kept and the near outliers are not.
#[test]
fn per_point_noise_keeps_far_points() {
    let truth = Isometry3::new(Vector3::new(0.2, -0.1, 1.0), Vector3::new(0.0, 0.05, 0.02));
    let mut rng = seeded(3);
    let (mut src, mut dst, mut sigma, mut inlier) = (vec![], vec![], vec![], vec![]);
    for i in 0..300 {
        let z: f64 = rng.random_range(3.0..40.0);
        let p = Point3::new(
            rng.random_range(-10.0..10.0),
            rng.random_range(-3.0..3.0),
            z,
        );
        let s_i = 0.004 * z * z / 10.0; // 0.4 cm at 3 m .. 64 cm at 40 m
        let noise = Normal::new(0.0, s_i).expect("valid sigma");
        let d = p + Vector3::new(
            noise.sample(&mut rng),
            noise.sample(&mut rng),
            noise.sample(&mut rng),
        );
        let wrong = i % 3 == 0; // a third of the matches are wrong
        src.push(truth.inverse_transform_point(&p));
        dst.push(if wrong {
            Point3::new(
                rng.random_range(-10.0..10.0),
                rng.random_range(-3.0..3.0),
                rng.random_range(3.0..40.0),
            )
        } else {
            d
        });
        sigma.push(s_i);
        inlier.push(!wrong);
    }
    let data = Correspondences::new(src, dst).expect("finite");
    let with_sigma = data.clone().with_noise_sigma(sigma).expect("valid sigma");
    let out = PsoEstimator::default()
        .estimate_seeded(&with_sigma, 4)
        .expect("solvable");
    let (r, t) = errors(&out.transform, &truth);
    assert!(r < 0.5 && t < 0.1, "{r} deg {t} m");
    let correct = out.inliers.iter().filter(|&&i| inlier[i]).count();
    let wrong = out.inliers.len() - correct;
    let total_correct = inlier.iter().filter(|&&b| b).count();
    assert!(
        correct * 100 >= total_correct * 90,
        "kept {correct}/{total_correct} correct"
    );
    assert!(
        wrong * 100 <= out.inliers.len() * 3,
        "{wrong} wrong matches accepted"
    );
    assert!(out.diagnostics.threshold_m.is_none());
    // One tight threshold loses most far points.
    let fixed = PsoEstimator::new(PsoEstimatorConfig::default().with_threshold(0.05))
        .estimate_seeded(&data, 4)
        .expect("solvable");
    let fixed_correct = fixed.inliers.iter().filter(|&&i| inlier[i]).count();
    assert!(
        fixed_correct < correct,
        "fixed {fixed_correct} vs per-point {correct}"
    );
}

#[test]
fn a_moving_object_covering_half_the_view_is_flagged() {
    // Half the matches follow the camera motion, half a moving object's.
    let truth = Isometry3::new(Vector3::new(0.3, 0.0, 0.5), Vector3::new(0.0, 0.08, 0.0));
    let object = Isometry3::new(Vector3::new(-1.0, 0.2, 0.0), Vector3::new(0.1, 0.0, -0.1));
    let mut rng = seeded(8);
    let (mut src, mut dst) = (vec![], vec![]);
    for i in 0..200 {
        let d = Point3::new(
            rng.random_range(-6.0..6.0),
            rng.random_range(-6.0..6.0),
            rng.random_range(2.0..25.0),
        );
        let motion = if i % 2 == 0 { truth } else { object };
        src.push(motion.inverse_transform_point(&d));
        dst.push(d);
    }
    let data = Correspondences::new(src, dst).expect("finite");
    let out = PsoEstimator::default()
        .estimate_seeded(&data, 1)
        .expect("solvable");
    assert!(out.is_ambiguous(), "a 50/50 split must be flagged");
    let second = out.diagnostics.runner_up.as_ref().expect("runner-up");
    let (a, _) = errors(&out.transform, &truth);
    let (b, _) = errors(&second.transform, &truth);
    // One of the two is the camera motion, the other the object's.
    assert!(a.min(b) < 0.01, "{a} {b}");
    assert!(second.inliers.len() * 10 >= out.inliers.len() * 9);
    // 80/20: not ambiguous.
    let keep: Vec<usize> = (0..200).filter(|i| i % 2 == 0 || i % 10 == 1).collect();
    let lopsided = data.select(&keep);
    let out = PsoEstimator::default()
        .estimate_seeded(&lopsided, 1)
        .expect("solvable");
    assert!(!out.is_ambiguous());
}

#[test]
fn anisotropic_stereo_noise_uses_the_covariances() {
    // Stereo-like noise (metres along the ray at 40 m, centimetres across), half the
    // matches wrong. With the covariances `pso` fits the Mahalanobis residuals; with only
    // the isotropic bound σ_i it must fit spheres as large as the depth noise.
    let (mut with_cov, mut iso_only) = (0, 0);
    for seed in 0..10 {
        let (data, truth, _) = crate::estimators::test_scenes::stereo_scene(40 + seed, 2);
        let sigma = data
            .noise_sigma()
            .expect("derived from the covariances")
            .to_vec();
        let iso = Correspondences::new(data.src().to_vec(), data.dst().to_vec())
            .and_then(|c| c.with_noise_sigma(sigma))
            .expect("valid");
        let ok = |c: &Correspondences| {
            PsoEstimator::default()
                .estimate_seeded(c, seed)
                .is_ok_and(|e| {
                    let (r, t) = errors(&e.transform, &truth);
                    r < 0.2 && t < 0.05
                })
        };
        with_cov += usize::from(ok(&data));
        iso_only += usize::from(ok(&iso));
    }
    println!("within 0.2 deg / 5 cm: {with_cov}/10 with covariances, {iso_only}/10 isotropic");
    assert!(with_cov >= 9, "{with_cov}/10 with covariances");
    assert!(with_cov > iso_only, "{with_cov} vs {iso_only}");
}

#[test]
fn a_larger_runner_up_becomes_the_winner() {
    // 60 % of the matches follow the camera's motion, 40 % a moving object's.
    let s = SyntheticSpec::default().generate(9).expect("valid");
    let object = Isometry3::new(Vector3::new(2.0, 0.0, 1.0), Vector3::new(0.0, 0.3, 0.0));
    let n = s.data.len();
    let on_object = |i: usize| i % 5 < 2;
    let dst: Vec<Point3<f64>> = (0..n)
        .map(|i| {
            if on_object(i) {
                object * s.data.src()[i]
            } else {
                s.data.dst()[i]
            }
        })
        .collect();
    let data = Correspondences::new(s.data.src().to_vec(), dst).expect("valid");
    let (camera_set, object_set): (Vec<usize>, Vec<usize>) = (0..n).partition(|&i| !on_object(i));
    let est = PsoEstimator::new(PsoEstimatorConfig::default().with_threshold(0.07));
    let mut found = Found {
        pose: object,
        inliers: object_set.clone(),
        iterations: 0,
        evaluations: 0,
    };
    let runner_up = RunnerUp {
        transform: s.truth,
        inliers: camera_set.clone(),
    };
    let reported =
        est.larger_consensus_wins(&data, &mut found, runner_up, Tolerance::Uniform(0.07));
    let (r, t) = errors(&found.pose, &s.truth);
    assert!(r < 0.1 && t < 0.02, "{r} deg, {t} m");
    assert_eq!(found.inliers.len(), camera_set.len());
    let reported = reported.expect("80 of 120 is above the ambiguity ratio");
    assert_eq!(reported.inliers, object_set);
    // A smaller runner-up stays the runner-up.
    let small = RunnerUp {
        transform: object,
        inliers: object_set,
    };
    let kept = est.larger_consensus_wins(&data, &mut found, small, Tolerance::Uniform(0.07));
    assert_eq!(kept.map(|r| r.inliers.len()), Some(80));
    assert_eq!(found.inliers.len(), camera_set.len());
}

#[test]
fn heavy_tailed_stereo_noise_without_covariances_keeps_the_consensus() {
    // Stereo-like points given as plain points (no noise model): residuals of far points
    // are metres along the ray, so the automatic threshold sees a heavy-tailed mix. The
    // final refinement must not trade the consensus for a fit of the tails. Measured:
    // worst translation error 0.12 m, fewest inliers 31 (a single threshold keeps the near
    // points); a mixture with a free noise scale drifted to 0.19 m here, and on KITTI
    // pairs to half a metre.
    let mut worst: (f64, usize) = (0.0, usize::MAX);
    for seed in 0..10 {
        let (with_cov, truth, _) = crate::estimators::test_scenes::stereo_scene(60 + seed, 4);
        let plain =
            Correspondences::new(with_cov.src().to_vec(), with_cov.dst().to_vec()).expect("valid");
        let e = PsoEstimator::default()
            .estimate_seeded(&plain, seed)
            .expect("estimate");
        let (_, t) = errors(&e.transform, &truth);
        worst = (worst.0.max(t), worst.1.min(e.inliers.len()));
    }
    println!(
        "worst translation error {:.3} m, fewest inliers {}",
        worst.0, worst.1
    );
    assert!(worst.0 < 0.15, "translation off by {:.3} m", worst.0);
    assert!(
        worst.1 >= 25,
        "only {} inliers of 150 correct matches",
        worst.1
    );
}

#[test]
fn one_point_at_1e10_metres_does_not_make_the_set_degenerate() {
    // 59 good correspondences and one wild one (a stereo point at near-zero disparity).
    let s = SyntheticSpec {
        n: 59,
        outlier_fraction: 0.0,
        ..SyntheticSpec::default()
    }
    .generate(4)
    .expect("valid");
    let mut src = s.data.src().to_vec();
    let mut dst = s.data.dst().to_vec();
    src.push(Point3::new(1e10, 2.0, 3.0));
    dst.push(Point3::new(-4.0, 1e10, 5.0));
    let data = Correspondences::new(src, dst).expect("finite");
    let out = PsoEstimator::default()
        .estimate_seeded(&data, 1)
        .expect("solvable");
    let (r, t) = errors(&out.transform, &s.truth);
    assert!(r < 0.5 && t < 0.1, "{r} deg, {t} m");
    assert!(!out.inliers.contains(&59));
    assert!(out.inliers.len() >= 55);
}

#[test]
fn chance_consensus_is_an_error_not_a_pose() {
    // Every match wrong: whatever the search settles on is chance agreement.
    for seed in 0..10 {
        let s = SyntheticSpec {
            n: 600,
            outlier_fraction: 1.0,
            ..SyntheticSpec::default()
        }
        .generate(100 + seed)
        .expect("valid");
        let r = PsoEstimator::default().estimate_seeded(&s.data, seed);
        assert!(
            matches!(r, Err(PoseError::InsufficientSupport { .. })),
            "seed {seed}: {:?}",
            r.map(|e| e.inliers.len())
        );
    }
}

#[test]
fn swarms_too_large_to_allocate_are_refused() {
    // 10^12 particles (or seeded particles) were allocated at once: the process aborted.
    let s = SyntheticSpec::default().generate(3).expect("valid");
    for config in [
        PsoEstimatorConfig {
            pso: crate::pso::PsoConfig::default().with_swarm_size(1_000_000_000_000),
            ..PsoEstimatorConfig::default()
        },
        PsoEstimatorConfig::default().with_seeded_particles(1_000_000_000_000),
    ] {
        let e = PsoEstimator::new(config)
            .estimate_seeded(&s.data, 0)
            .expect_err("too many particles");
        assert!(
            e.to_string().contains("is 1000000000000: it must be from ")
                && e.to_string().contains(" to 1000000"),
            "{e}"
        );
    }
}
