//! Property tests: proper rotations always, SVD exact on noise-free data, reproducibility.

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use proptest::prelude::*;
use swarmpose_core::synthetic::SyntheticSpec;
use swarmpose_core::{
    Correspondences, Estimator, MsacEstimator, PsoEstimator, PsoPaperEstimator, SvdEstimator,
};

fn estimators() -> Vec<Box<dyn Estimator>> {
    vec![
        Box::new(PsoEstimator::default()),
        Box::new(PsoPaperEstimator::default()),
        Box::new(SvdEstimator),
        Box::new(MsacEstimator::default()),
    ]
}

fn assert_proper(q: &UnitQuaternion<f64>) {
    let r = q.to_rotation_matrix().into_inner();
    assert!(
        (r.determinant() - 1.0).abs() < 1e-9,
        "det {}",
        r.determinant()
    );
    assert!((r * r.transpose() - nalgebra::Matrix3::identity()).norm() < 1e-9);
}

fn point() -> impl Strategy<Value = Point3<f64>> {
    (-100.0..100.0f64, -100.0..100.0f64, -100.0..100.0f64)
        .prop_map(|(x, y, z)| Point3::new(x, y, z))
}

/// A rotation with any axis and an angle in [0, π], weighted towards 0 and π.
fn rotation() -> impl Strategy<Value = UnitQuaternion<f64>> {
    let angle = prop_oneof![
        0.0..std::f64::consts::PI,
        (std::f64::consts::PI - 1e-6)..=std::f64::consts::PI,
        0.0..1e-6f64,
    ];
    ((-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64), angle).prop_filter_map(
        "axis must not vanish",
        |((x, y, z), a)| {
            let v = Vector3::new(x, y, z);
            (v.norm() > 1e-3).then(|| UnitQuaternion::from_axis_angle(&Unit::new_normalize(v), a))
        },
    )
}

fn pose() -> impl Strategy<Value = Isometry3<f64>> {
    (rotation(), (-50.0..50.0f64, -50.0..50.0f64, -50.0..50.0f64))
        .prop_map(|(q, (x, y, z))| Isometry3::from_parts(Translation3::new(x, y, z), q))
}

/// Point sets in general position, or lying on a random plane.
fn cloud() -> impl Strategy<Value = Vec<Point3<f64>>> {
    let general = prop::collection::vec(point(), 4..40);
    let planar = (
        prop::collection::vec((-20.0..20.0f64, -20.0..20.0f64), 4..40),
        pose(),
    )
        .prop_map(|(uv, plane)| {
            uv.into_iter()
                .map(|(u, v)| plane * Point3::new(u, v, 0.0))
                .collect()
        });
    prop_oneof![general, planar]
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(48))]

    /// Any finite input: every estimator either errs or returns a proper rotation.
    #[test]
    fn every_rotation_is_proper(src in prop::collection::vec(point(), 4..30),
                                dst in prop::collection::vec(point(), 4..30),
                                seed in any::<u64>()) {
        let n = src.len().min(dst.len());
        let data = Correspondences::new(src[..n].to_vec(), dst[..n].to_vec()).expect("finite");
        for e in estimators() {
            if let Ok(out) = e.estimate_seeded(&data, seed) {
                assert_proper(&out.transform.rotation);
                prop_assert!(out.transform.translation.vector.iter().all(|v| v.is_finite()));
                prop_assert!(out.inliers.windows(2).all(|w| w[0] < w[1]));
            }
        }
    }

    /// SVD recovers any pose exactly from noise-free data, planar sets and rotations near
    /// 180 degrees included.
    #[test]
    fn svd_exact_on_noise_free_data(src in cloud(), truth in pose()) {
        prop_assume!(swarmpose_core::geometry::spread(&src)[1] > 1e-3);
        let dst = src.iter().map(|p| truth * p).collect();
        let data = Correspondences::new(src, dst).expect("finite");
        let out = SvdEstimator.estimate_seeded(&data, 0).expect("solvable");
        assert_proper(&out.transform.rotation);
        let dr = (out.transform.rotation.to_rotation_matrix().into_inner()
            - truth.rotation.to_rotation_matrix().into_inner()).norm();
        let dt = (out.transform.translation.vector - truth.translation.vector).norm();
        prop_assert!(dr < 1e-9, "rotation off by {dr}");
        prop_assert!(dt < 1e-9, "translation off by {dt}");
    }

    /// One seed, one answer, for every estimator.
    #[test]
    fn same_seed_same_output(scenario_seed in 0u64..1000, outliers in 0.0..0.6f64, seed in any::<u64>()) {
        let s = SyntheticSpec { outlier_fraction: outliers, n: 60, ..Default::default() }
            .generate(scenario_seed).expect("valid");
        for e in estimators() {
            let a = e.estimate_seeded(&s.data, seed);
            let b = e.estimate_seeded(&s.data, seed);
            match (a, b) {
                (Ok(a), Ok(b)) => {
                    prop_assert_eq!(a.transform, b.transform);
                    prop_assert_eq!(a.inliers, b.inliers);
                }
                (Err(a), Err(b)) => prop_assert_eq!(a, b),
                _ => prop_assert!(false, "{}: runs differ", e.name()),
            }
        }
    }
}

/// `data` with every coordinate multiplied by `k`.
fn scaled(data: &Correspondences, k: f64) -> Correspondences {
    let s = |v: &[Point3<f64>]| v.iter().map(|p| p * k).collect::<Vec<_>>();
    Correspondences::new(s(data.src()), s(data.dst())).expect("finite")
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(24))]

    /// The default `pso` does not depend on the unit: on data scaled by k its estimate is
    /// the original's scaled by k (rotation within 1e-4 rad, translation within 1e-4 k,
    /// inlier sets differing by at most 1 %).
    #[test]
    fn pso_is_scale_invariant(
        seed in 0u64..1000,
        log_k in -3.0f64..3.0,
        outliers in 0.0f64..0.9,
    ) {
        let k = 10f64.powf(log_k);
        let spec = SyntheticSpec { outlier_fraction: outliers, ..SyntheticSpec::default() };
        let s = spec.generate(seed).expect("valid");
        let a = PsoEstimator::default().estimate_seeded(&s.data, seed);
        let b = PsoEstimator::default().estimate_seeded(&scaled(&s.data, k), seed);
        match (a, b) {
            (Ok(a), Ok(b)) => {
                let r = a.transform.rotation.angle_to(&b.transform.rotation);
                let t = (a.transform.translation.vector * k - b.transform.translation.vector).norm();
                prop_assert!(r < 1e-4, "rotation differs by {r} rad at k = {k}");
                prop_assert!(t < 1e-4 * k, "translation differs by {t} at k = {k}");
                let sa: std::collections::BTreeSet<usize> = a.inliers.iter().copied().collect();
                let sb: std::collections::BTreeSet<usize> = b.inliers.iter().copied().collect();
                let differ = sa.symmetric_difference(&sb).count();
                prop_assert!(differ * 100 <= sa.len().max(sb.len()), "{differ} inliers differ at k = {k}");
                let (da, db) = (a.diagnostics.threshold_m, b.diagnostics.threshold_m);
                prop_assert!(da.zip(db).is_some_and(|(x, y)| (y / (x * k) - 1.0).abs() < 1e-3));
            }
            (Err(_), Err(_)) => {}
            (a, b) => prop_assert!(false, "one failed at k = {k}: {:?} / {:?}", a.err(), b.err()),
        }
    }
}
