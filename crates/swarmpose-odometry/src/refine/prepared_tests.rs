//! [`Prepared`] against [`StereoModel`]'s methods, bit for bit, on seeded random models,
//! poses, points and measurements with zeros of both signs, NaNs and infinities.

use nalgebra::{Matrix3, Rotation3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use swarmpose_vision::frontend::{CORRECTION_TERMS, DisparityCorrection};

use super::Prepared;
use crate::refine::model::{Linearized, Parts, StereoModel, StereoObservation, test_model};

/// The same bits, or both NaN (Rust leaves a NaN's sign and payload unspecified).
fn same(a: f64, b: f64) -> bool {
    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan())
}

fn same_slices(a: &[f64], b: &[f64]) -> bool {
    a.len() == b.len() && a.iter().zip(b).all(|(x, y)| same(*x, *y))
}

fn same_linearized(a: &Linearized, b: &Linearized) -> bool {
    same_slices(a.residual.as_slice(), b.residual.as_slice())
        && same_slices(a.d_point.as_slice(), b.d_point.as_slice())
        && same_slices(a.d_pose.as_slice(), b.d_pose.as_slice())
        && same_slices(a.d_correction.as_slice(), b.d_correction.as_slice())
        && same_slices(a.d_h.as_slice(), b.d_h.as_slice())
}

/// A value of the usual size, or now and then a special one.
fn value(rng: &mut ChaCha8Rng, scale: f64) -> f64 {
    match rng.random_range(0..40) {
        0 => 0.0,
        1 => -0.0,
        2 => f64::NAN,
        3 => f64::INFINITY,
        _ => rng.random_range(-scale..scale),
    }
}

fn model(rng: &mut ChaCha8Rng) -> StereoModel {
    let mut c = [0.0; CORRECTION_TERMS];
    for v in &mut c {
        *v = match rng.random_range(0..4) {
            0 => 0.0,
            1 => -0.0,
            _ => value(rng, 3.0),
        };
    }
    let mut m = test_model(DisparityCorrection::from_coefficients(c));
    if rng.random_range(0..4) == 0 {
        m.rig.fx += value(rng, 50.0);
        m.noise.disparity_px = rng.random_range(0.05..1.0);
    }
    m
}

#[test]
fn prepared_is_the_model_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(37);
    let mut in_front = 0;
    for _ in 0..20_000 {
        let m = model(&mut rng);
        let prepared = Prepared::new(&m);
        let rot = *Rotation3::from_euler_angles(
            rng.random_range(-0.1..0.1),
            rng.random_range(-0.1..0.1),
            rng.random_range(-0.1..0.1),
        )
        .matrix();
        let rot = if rng.random_range(0..50) == 0 {
            Matrix3::identity()
        } else {
            rot
        };
        let trans = Vector3::new(
            value(&mut rng, 0.3),
            value(&mut rng, 0.3),
            value(&mut rng, 2.0),
        );
        let p = Vector3::new(
            value(&mut rng, 0.8),
            value(&mut rng, 0.3),
            match rng.random_range(0..10) {
                0 => 0.0,
                1 => -0.0,
                _ => rng.random_range(0.0..0.5),
            },
        );
        let z = |rng: &mut ChaCha8Rng| StereoObservation {
            u: value(rng, 1200.0),
            v: value(rng, 370.0),
            d: value(rng, 80.0),
        };
        let (a, b) = (z(&mut rng), z(&mut rng));
        let (pa, ma) = (prepared.anchor(&a), m.anchor(&a));
        assert!(same_slices(pa.as_slice(), ma.as_slice()), "anchor {a:?}");
        assert!(same(
            prepared.residual2_in_reference(&p, &a),
            m.residual2_in_reference(&p, &a)
        ));
        let (got, want) = (
            prepared.residuals2(&rot, &trans, &p, &a, &b),
            m.residuals2(&rot, &trans, &p, &a, &b),
        );
        assert_eq!(got.is_some(), want.is_some());
        if let (Some(g), Some(w)) = (got, want) {
            assert!(same(g.0, w.0) && same(g.1, w.1), "{g:?} {w:?}");
            in_front += 1;
        }
        for parts in [Parts::Point, Parts::PointPose, Parts::All] {
            let (g, w) = (
                prepared.in_reference_parts(&p, &a, parts),
                m.in_reference_parts(&p, &a, parts),
            );
            assert!(same_linearized(&g, &w), "in A, {parts:?}: {g:?} {w:?}");
            let (g, w) = (
                prepared.in_current_parts(&rot, &trans, &p, &b, parts),
                m.in_current_parts(&rot, &trans, &p, &b, parts),
            );
            assert_eq!(g.is_some(), w.is_some());
            if let (Some(g), Some(w)) = (g, w) {
                assert!(same_linearized(&g, &w), "in B, {parts:?}: {g:?} {w:?}");
            }
        }
    }
    // Most cases reach the current frame's linearisation.
    assert!(in_front > 10_000, "{in_front}");
}

/// The inlined correction is `at_normalised` bit for bit, zeros of both signs included
/// (its sum starts from `−0`).
#[test]
fn the_inlined_correction_is_at_normalised() {
    let mut rng = ChaCha8Rng::seed_from_u64(38);
    for _ in 0..20_000 {
        let c = DisparityCorrection::from_coefficients(std::array::from_fn(|_| {
            match rng.random_range(0..3) {
                0 => -0.0,
                1 => 0.0,
                _ => value(&mut rng, 5.0),
            }
        }));
        let x = value(&mut rng, 1.0);
        let y = value(&mut rng, 1.0);
        let (g, w) = (super::correction_at(&c, x, y), c.at_normalised(x, y));
        assert!(same(g, w), "{c:?} at ({x}, {y}): {g} against {w}");
    }
    let c = DisparityCorrection::from_coefficients([-0.0; CORRECTION_TERMS]);
    assert_eq!(
        super::correction_at(&c, 0.0, 0.0).to_bits(),
        (-0.0_f64).to_bits()
    );
}
