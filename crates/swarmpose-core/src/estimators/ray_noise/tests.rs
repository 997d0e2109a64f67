//! Tests of the range noise model and its choice.

use nalgebra::{Translation3, Vector3};

use super::*;
use crate::estimators::test_scenes::stereo_scene;
use crate::synthetic::SyntheticSpec;

#[test]
fn the_ray_model_is_chosen_for_stereo_noise_only() {
    for seed in 0..5 {
        let (data, truth, _) = stereo_scene(seed, 5);
        let plain = Correspondences::new(data.src().to_vec(), data.dst().to_vec()).expect("valid");
        assert!(
            choose(&plain, &truth, 0.3, 0.1).is_some(),
            "stereo scene {seed}: isotropic chosen"
        );
        let spec = SyntheticSpec {
            outlier_fraction: 0.5,
            ..SyntheticSpec::default()
        };
        let s = spec.generate(seed).expect("valid");
        assert!(
            choose(&s.data, &s.truth, 3.368 * 0.02, 0.02).is_none(),
            "isotropic scene {seed}: ray model chosen"
        );
    }
}

#[test]
fn the_choice_does_not_depend_on_the_unit() {
    let (data, truth, _) = stereo_scene(3, 5);
    let k = 1000.0;
    let scaled = Correspondences::new(
        data.src().iter().map(|p| p * k).collect(),
        data.dst().iter().map(|p| p * k).collect(),
    )
    .expect("valid");
    let plain = Correspondences::new(data.src().to_vec(), data.dst().to_vec()).expect("valid");
    let truth_k = Isometry3::from_parts(
        Translation3::from(truth.translation.vector * k),
        truth.rotation,
    );
    let a = choose(&plain, &truth, 0.3, 0.1).expect("ray");
    let b = choose(&scaled, &truth_k, 0.3 * k, 0.1 * k).expect("ray");
    assert!((b.floor / (a.floor * k * k) - 1.0).abs() < 1e-6);
    assert!((b.along * k * k / a.along - 1.0).abs() < 1e-6);
    assert!((b.across / a.across - 1.0).abs() < 1e-6);
}

#[test]
fn covariance_is_along_and_across_the_ray() {
    let m = RangeNoise::from_array([1e-4, 1e-3, 1e-2]);
    let p = Point3::new(0.0, 0.0, 2.0);
    let c = m.covariance(&p);
    assert!((c[(2, 2)] - (1e-4 + 1e-3 * 16.0)).abs() < 1e-12);
    assert!((c[(0, 0)] - (1e-4 + 1e-2 * 4.0)).abs() < 1e-12);
    let u = Vector3::new(1.0, 0.0, 0.0);
    assert!((u.dot(&(c * u)) - c[(0, 0)]).abs() < 1e-15);
}

#[test]
fn the_fits_have_the_same_bits_in_every_instruction_set() {
    let bits = |f: &Fitted| {
        let p = &f.pose;
        let mut v: Vec<u64> = [
            p.translation.vector.as_slice(),
            p.rotation.coords.as_slice(),
        ]
        .concat()
        .iter()
        .map(|x| x.to_bits())
        .collect();
        v.extend(f.noise.as_array().map(f64::to_bits));
        v.push(f.log_likelihood.to_bits());
        (v, f.inlier.clone())
    };
    for seed in 0..4 {
        let (data, truth, _) = stereo_scene(seed, 3);
        let plain = Correspondences::new(data.src().to_vec(), data.dst().to_vec()).expect("valid");
        for ray in [true, false] {
            let start = RangeNoise::from_array([1e-4, if ray { 1e-7 } else { 0.0 }, 0.0]);
            let fit = || em(&plain, &truth, 0.3, start, 1e-12, ray, f64::INFINITY);
            let (a, b) = (fit(), crate::simd::baseline(fit));
            assert_eq!(
                a.as_ref().map(bits),
                b.as_ref().map(bits),
                "seed {seed}, ray {ray}"
            );
        }
        let choice = |d: &Correspondences| choose(d, &truth, 0.3, 0.1).map(|n| n.as_array());
        assert_eq!(
            choice(&plain).map(|a| a.map(f64::to_bits)),
            crate::simd::baseline(|| choice(&plain)).map(|a| a.map(f64::to_bits)),
        );
    }
}

/// The isotropic M step's sums before their kernel (issue 34), dispatched and baseline, on
/// seeded random rows (weights below `MIN_WEIGHT`, zeros of both signs).
#[test]
fn isotropic_sums_match_the_reference_in_every_instruction_set() {
    use nalgebra::{Isometry3, Matrix3};
    use rand::RngExt;
    let mut rng = crate::rng::seeded(44);
    for case in 0..100 {
        let n: usize = rng.random_range(1..150);
        let (src, dst) =
            crate::estimators::test_scenes::random_clouds(&mut rng, n, -3.0..3.0, 1.0..9.0);
        let data = Correspondences::new(src, dst).expect("valid");
        let pose = Isometry3::new(
            Vector3::new(rng.random_range(-1.0..1.0), 0.0, 0.2),
            Vector3::new(0.0, rng.random_range(-0.5..0.5), 0.0),
        );
        let rows: Vec<Row> = (0..n)
            .map(|_| Row {
                weight: match rng.random_range(0..10) {
                    0 => 0.0,
                    1 => -0.0,
                    2 => rng.random_range(0.0..2.0 * MIN_WEIGHT),
                    _ => rng.random_range(0.0..1.0),
                },
                information: Matrix3::identity(),
            })
            .collect();
        let (mut num, mut den) = (0.0f64, 0.0f64);
        for (i, row) in rows.iter().enumerate() {
            if row.weight < MIN_WEIGHT {
                continue;
            }
            num += row.weight * (data.dst()[i] - pose * data.src()[i]).norm_squared();
            den += 3.0 * row.weight;
        }
        let kernel = || {
            let (a, b) = crate::simd::dispatch(IsotropicSums {
                data: &data,
                pose: &pose,
                rows: &rows,
            });
            (a.to_bits(), b.to_bits())
        };
        let expected = (num.to_bits(), den.to_bits());
        assert_eq!(kernel(), expected, "case {case}");
        assert_eq!(crate::simd::baseline(kernel), expected, "case {case}");
    }
}
