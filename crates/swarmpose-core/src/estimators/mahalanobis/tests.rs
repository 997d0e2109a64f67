//! Tests of the Mahalanobis refinement and its kernels.

use nalgebra::{Point3, Vector3};

use super::*;
use crate::arun::arun;
use crate::estimators::test_scenes::{moved_after, stereo_scene};
use crate::geometry::rotation_angle_between;

#[test]
fn beats_isotropic_least_squares_on_stereo_noise() {
    let (mut better, mut within) = (0, 0);
    for seed in 0..10 {
        let (data, truth, inlier) = stereo_scene(seed, 5);
        let (pose, inliers) = refine_mahalanobis(&data, &truth, CHI2_3_99, 10).expect("refined");
        let idx: Vec<usize> = (0..data.len()).filter(|&i| inlier[i]).collect();
        let sel = data.select(&idx);
        let ls = arun(sel.src(), sel.dst()).expect("fit");
        let err = |p: &Isometry3<f64>| (p.translation.vector - truth.translation.vector).norm();
        better += usize::from(err(&pose) < err(&ls));
        within += usize::from(
            err(&pose) < 0.05
                && rotation_angle_between(&pose.rotation, &truth.rotation).to_degrees() < 0.2,
        );
        assert!(
            inliers.iter().all(|&i| inlier[i]),
            "a wrong match passed the gate"
        );
        assert!(
            inliers.len() as f64 > 0.9 * idx.len() as f64,
            "{} of {} inliers",
            inliers.len(),
            idx.len()
        );
    }
    assert!(
        better >= 9,
        "Mahalanobis beat isotropic least squares on the true inliers {better}/10"
    );
    assert_eq!(within, 10);
}

/// The point update of the normal equations on nalgebra's 6-row columns, as it was before
/// [`Normal`] (issue 34): the reference.
fn add_point_before(
    h: &mut Matrix6<f64>,
    g: &mut Vector6<f64>,
    pose: &Isometry3<f64>,
    data: &Correspondences,
    i: usize,
    w: &Matrix3<f64>,
) {
    let q = (pose * data.src()[i]).coords;
    let r = data.dst()[i].coords - q;
    let (q0, q1, q2) = (q[0], q[1], q[2]);
    let columns = &w.data.0;
    let pc: [[f64; 6]; 3] = std::array::from_fn(|b| {
        let col = &columns[b];
        [
            q2 * col[1] + (-q1) * col[2],
            (-q2) * col[0] + q0 * col[2],
            q1 * col[0] + (-q0) * col[1],
            -col[0],
            -col[1],
            -col[2],
        ]
    });
    let lanes: [f64; 6] = std::array::from_fn(|a| pc[0][a] + pc[1][a] + pc[2][a]);
    let total = (lanes[0] + lanes[1]) + (lanes[2] + lanes[3]) + (lanes[4] + lanes[5]);
    if !total.is_finite() {
        add_point_full(h, g, &q, &r, w);
        return;
    }
    let [p0, p1, p2] = &pc;
    let hc = &mut h.data.0;
    for a in 0..6 {
        hc[0][a] += p1[a] * q2 + p2[a] * (-q1);
        hc[1][a] += p0[a] * (-q2) + p2[a] * q0;
        hc[2][a] += p0[a] * q1 + p1[a] * (-q0);
    }
    for (k, pk) in pc.iter().enumerate() {
        for a in 0..6 {
            hc[3 + k][a] += -pk[a];
        }
    }
    let gc = &mut g.data.0[0];
    for a in 0..6 {
        gc[a] += p0[a] * r[0] + p1[a] * r[1] + p2[a] * r[2];
    }
}

#[test]
fn add_point_has_the_bits_of_the_full_products() {
    use rand::RngExt;
    let mut rng = crate::rng::seeded(34);
    let value = |rng: &mut crate::rng::SeededRng| -> f64 {
        match rng.random_range(0..12) {
            0 => 0.0,
            1 => -0.0,
            _ => rng.random_range(-50.0..50.0),
        }
    };
    for case in 0..400 {
        let n = 1 + case % 11;
        let src: Vec<Point3<f64>> = (0..n)
            .map(|_| Point3::new(value(&mut rng), value(&mut rng), value(&mut rng)))
            .collect();
        let dst: Vec<Point3<f64>> = (0..n)
            .map(|_| Point3::new(value(&mut rng), value(&mut rng), value(&mut rng)))
            .collect();
        let data = Correspondences::new(src, dst).expect("valid");
        let axis = Vector3::new(value(&mut rng), value(&mut rng), value(&mut rng)) * 0.01;
        let pose = Isometry3::new(
            Vector3::new(value(&mut rng), value(&mut rng), value(&mut rng)),
            axis,
        );
        let (mut h, mut g) = (Matrix6::<f64>::zeros(), Vector6::<f64>::zeros());
        let (mut h_ref, mut g_ref) = (Matrix6::<f64>::zeros(), Vector6::<f64>::zeros());
        let mut normal = Normal::zeros();
        for i in 0..n {
            let mut w = Matrix3::from_fn(|_, _| value(&mut rng));
            if case % 4 == 0 {
                w = w * w.transpose(); // symmetric, as an information is
            }
            match rng.random_range(0..20) {
                0 => w[(rng.random_range(0..3), rng.random_range(0..3))] = f64::NAN,
                1 => w[(rng.random_range(0..3), rng.random_range(0..3))] = f64::INFINITY,
                2 => w *= 1e307, // P overflows
                _ => {}
            }
            add_point_before(&mut h, &mut g, &pose, &data, i, &w);
            normal.add_point(&pose, &data, i, &w);
            let q = (pose * data.src()[i]).coords;
            let r = data.dst()[i].coords - q;
            add_point_full(&mut h_ref, &mut g_ref, &q, &r, &w);
        }
        let bits = |m: &[f64]| m.iter().map(|v| v.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(h.as_slice()), bits(h_ref.as_slice()), "h, case {case}");
        assert_eq!(bits(g.as_slice()), bits(g_ref.as_slice()), "g, case {case}");
        // The register layout: the same bits as the 6-row columns (NaN included).
        let (h_new, g_new) = normal.parts();
        assert_eq!(bits(h_new.as_slice()), bits(h.as_slice()), "h, case {case}");
        assert_eq!(bits(g_new.as_slice()), bits(g.as_slice()), "g, case {case}");
    }
}

/// One draw of the bit tests' inputs: of `cases` equally likely cases, 0, -0, NaN and
/// infinity one each, else uniform in `(-half_width, half_width)`.
fn special_or_uniform(rng: &mut crate::rng::SeededRng, cases: u32, half_width: f64) -> f64 {
    use rand::RngExt;
    match rng.random_range(0..cases) {
        0 => 0.0,
        1 => -0.0,
        2 => f64::NAN,
        3 => f64::INFINITY,
        _ => rng.random_range(-half_width..half_width),
    }
}

#[test]
fn normal_equations_have_the_same_bits_in_every_instruction_set() {
    use rand::RngExt;
    let mut rng = crate::rng::seeded(37);
    let value = |rng: &mut crate::rng::SeededRng| special_or_uniform(rng, 40, 20.0);
    // Every NaN as one: Rust leaves a NaN's sign and payload unspecified (x86 passes on
    // the first operand's NaN, and SSE and AVX code may order the operands of a
    // commutative operation differently); the callers only ask whether a value is finite.
    let bits = |m: &[f64]| {
        m.iter()
            .map(|v| if v.is_nan() { u64::MAX } else { v.to_bits() })
            .collect::<Vec<u64>>()
    };
    for case in 0..200 {
        let n = 40;
        // Points and poses finite (the correspondences reject others); covariances any.
        let finite = |rng: &mut crate::rng::SeededRng| {
            let v = value(rng);
            if v.is_finite() { v } else { -0.0 }
        };
        let point =
            |rng: &mut crate::rng::SeededRng| Point3::new(finite(rng), finite(rng), finite(rng));
        let src: Vec<Point3<f64>> = (0..n).map(|_| point(&mut rng)).collect();
        let dst: Vec<Point3<f64>> = (0..n).map(|_| point(&mut rng)).collect();
        let cov = |rng: &mut crate::rng::SeededRng| {
            let a = Matrix3::from_fn(|_, _| value(rng));
            if rng.random_range(0..4) == 0 {
                a
            } else {
                a * a.transpose()
            }
        };
        let sc: Vec<Matrix3<f64>> = (0..n).map(|_| cov(&mut rng)).collect();
        let dc: Vec<Matrix3<f64>> = (0..n).map(|_| cov(&mut rng)).collect();
        let data = Correspondences::new(src, dst).expect("valid");
        let axis = Vector3::new(finite(&mut rng), finite(&mut rng), finite(&mut rng)) * 0.01;
        let t = Vector3::new(finite(&mut rng), finite(&mut rng), finite(&mut rng));
        let pose = Isometry3::new(t, axis);
        let rows: Vec<usize> = (0..n).filter(|_| rng.random_range(0..3) > 0).collect();
        let kernel = || NormalEquations {
            pose: &pose,
            data: &data,
            covariance: (&sc, &dc),
            rows: &rows,
        };
        let (h, g) = simd::dispatch(kernel());
        let (h_ref, g_ref) = simd::baseline(|| simd::dispatch(kernel()));
        assert_eq!(bits(h.as_slice()), bits(h_ref.as_slice()), "h, case {case}");
        assert_eq!(bits(g.as_slice()), bits(g_ref.as_slice()), "g, case {case}");
    }
    // And whole refinements on stereo scenes.
    for seed in 0..4 {
        let (data, truth, _) = stereo_scene(seed, 5);
        let fit = || refine_mahalanobis(&data, &truth, CHI2_3_99, 10).expect("refined");
        let ((pose, inliers), (pose_ref, inliers_ref)) = (fit(), simd::baseline(fit));
        assert_eq!(inliers, inliers_ref);
        let pose_bits = |p: &Isometry3<f64>| {
            bits(
                &[
                    p.translation.vector.as_slice(),
                    p.rotation.coords.as_slice(),
                ]
                .concat(),
            )
        };
        assert_eq!(pose_bits(&pose), pose_bits(&pose_ref), "scene {seed}");
    }
}

/// The gate's selection as it was before its kernel (issue 34): the reference.
fn select_reference(
    data: &Correspondences,
    (src_cov, dst_cov): CovariancePair<'_>,
    pose: &Isometry3<f64>,
    gate: f64,
) -> Vec<usize> {
    let rot = pose.rotation.to_rotation_matrix();
    (0..data.len())
        .filter(|&i| {
            let r = data.dst()[i] - pose * data.src()[i];
            r.norm_squared() < gate * (src_cov[i].trace() + dst_cov[i].trace())
                && inverse3(&(rot.matrix() * src_cov[i] * rot.matrix().transpose() + dst_cov[i]))
                    .is_some_and(|w| r.dot(&(w * r)) < gate)
        })
        .collect()
}

#[test]
fn selection_matches_the_reference_in_every_instruction_set() {
    use rand::RngExt;
    let mut rng = crate::rng::seeded(41);
    let value = |rng: &mut crate::rng::SeededRng| special_or_uniform(rng, 60, 3.0);
    let mut selected = 0;
    for case in 0..200 {
        let n = 60;
        let (src, dst) =
            crate::estimators::test_scenes::random_clouds(&mut rng, n, -2.0..2.0, -2.0..2.0);
        let cov = |rng: &mut crate::rng::SeededRng| {
            let a = Matrix3::from_fn(|_, _| value(rng));
            if rng.random_range(0..4) == 0 {
                a
            } else {
                a * a.transpose()
            }
        };
        let sc: Vec<Matrix3<f64>> = (0..n).map(|_| cov(&mut rng)).collect();
        let dc: Vec<Matrix3<f64>> = (0..n).map(|_| cov(&mut rng)).collect();
        let data = Correspondences::new(src, dst).expect("valid");
        let pose = Isometry3::new(
            Vector3::new(
                rng.random_range(-0.5..0.5),
                rng.random_range(-0.5..0.5),
                0.0,
            ),
            Vector3::new(0.0, rng.random_range(-0.3..0.3), 0.01),
        );
        let gate = [CHI2_3_99, 4.0 * CHI2_3_99, 16.0 * CHI2_3_99][case % 3];
        let expected = select_reference(&data, (&sc, &dc), &pose, gate);
        selected += expected.len();
        let run = || {
            let mut out = vec![usize::MAX; 3];
            simd::dispatch(Select {
                pose: &pose,
                data: &data,
                covariance: (&sc, &dc),
                gate,
                out: &mut out,
            });
            out
        };
        assert_eq!(run(), expected, "case {case}");
        assert_eq!(simd::baseline(run), expected, "case {case}");
    }
    // Rows on both sides of the gate: the test compares selections, not empty lists.
    assert!(
        selected > 0 && selected < 200 * 60,
        "{selected} rows selected"
    );
}

#[test]
fn determinant_and_inverse_have_nalgebras_bits() {
    use rand::RngExt;
    let mut rng = crate::rng::seeded(35);
    let bits = |m: &Matrix3<f64>| m.iter().map(|v| v.to_bits()).collect::<Vec<u64>>();
    for case in 0..4000 {
        let mut m = Matrix3::from_fn(|_, _| match rng.random_range(0..10) {
            0 => 0.0,
            1 => -0.0,
            2 => rng.random_range(-3..=3) as f64, // small integers: exact zero determinants
            _ => rng.random_range(-1e3..1e3),
        });
        match case % 7 {
            0 => m = m * m.transpose(), // symmetric, as a covariance is
            1 => m[(rng.random_range(0..3), rng.random_range(0..3))] = f64::NAN,
            2 => m[(rng.random_range(0..3), rng.random_range(0..3))] = f64::NEG_INFINITY,
            3 => m *= 1e-120, // the determinant underflows
            4 => m *= 1e110,  // the determinant overflows
            5 => m.set_column(2, &m.column(0).clone_owned()), // singular
            _ => {}
        }
        let (det, inverse) = determinant_and_inverse(&m);
        assert_eq!(det.to_bits(), m.determinant().to_bits(), "case {case}: {m}");
        let expected = m.try_inverse();
        assert_eq!(inverse.is_some(), expected.is_some(), "case {case}: {m}");
        if let (Some(a), Some(b)) = (inverse, expected) {
            assert_eq!(bits(&a), bits(&b), "case {case}: {m}");
        }
        assert_eq!(inverse3(&m).map(|a| bits(&a)), inverse.map(|a| bits(&a)));
    }
}

#[test]
fn needs_covariances_and_support() {
    let p = |x: f64, y: f64, z: f64| Point3::new(x, y, z);
    let pts = vec![
        p(0.0, 0.0, 1.0),
        p(1.0, 0.0, 2.0),
        p(0.0, 1.0, 3.0),
        p(1.0, 1.0, 5.0),
        p(2.0, 0.5, 4.0),
    ];
    let plain = Correspondences::new(pts.clone(), pts.clone()).expect("valid");
    let id = Isometry3::identity();
    assert!(matches!(
        refine_mahalanobis(&plain, &id, CHI2_3_99, 5),
        Err(PoseError::InvalidConfig(_))
    ));
    let cov = vec![Matrix3::identity() * 1e-4; 5];
    let far = moved_after(&pts, 2, |_| Vector3::new(9.0, 0.0, 0.0));
    let data = Correspondences::new(pts, far)
        .and_then(|c| c.with_noise_covariance(cov.clone(), cov))
        .expect("valid");
    assert!(matches!(
        refine_mahalanobis(&data, &id, CHI2_3_99, 5),
        Err(PoseError::InsufficientSupport { .. })
    ));
    assert!(refine_mahalanobis(&data, &id, f64::NAN, 5).is_err());
}
