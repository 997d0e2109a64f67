//! Tests of the window's bundle adjustment.

use super::*;
use crate::refine::model::StereoObservation;
use crate::window::residual::linearize;
use nalgebra::Rotation3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Central differences of the residual against both pose Jacobians.
#[test]
fn pose_jacobians_match_finite_differences() {
    let model = crate::refine::model::test_model(Default::default());
    let pose = |r: (f64, f64, f64), t: [f64; 3]| Pose {
        rot: *Rotation3::from_euler_angles(r.0, r.1, r.2).matrix(),
        trans: Vector3::from(t),
    };
    let poses = [
        pose((0.0, 0.0, 0.0), [0.0, 0.0, 0.0]),
        pose((0.01, -0.03, 0.02), [0.1, -0.05, -0.9]),
        pose((0.02, -0.07, 0.01), [0.3, -0.02, -1.8]),
    ];
    let p = Vector3::new(0.2, -0.1, 1.0 / 14.0);
    let z = StereoObservation {
        u: 740.0,
        v: 120.0,
        d: 27.0,
    };
    let (anchor, slot) = (1, 2);
    let mut rel = Vec::new();
    relative_poses(&poses, &mut rel);
    let j = linearize(&model, (&rel, 3), anchor, slot, &p, &z).expect("in view");
    let (dj, da) = j.poses.expect("two keyframes");
    let h = 1e-6;
    for (which, analytic) in [(slot, dj), (anchor, da)] {
        for k in 0..6 {
            let residual = |s: f64| {
                let mut xi = [0.0; 6];
                xi[k] = s * h;
                let mut moved = poses;
                moved[which] = poses[which].moved(
                    &Vector3::new(xi[0], xi[1], xi[2]),
                    &Vector3::new(xi[3], xi[4], xi[5]),
                );
                let mut rel = Vec::new();
                relative_poses(&moved, &mut rel);
                linearize(&model, (&rel, 3), anchor, slot, &p, &z)
                    .expect("in view")
                    .residual
            };
            let num = (residual(1.0) - residual(-1.0)) / (2.0 * h);
            assert!(
                (num - analytic.column(k)).norm() < 1e-4 * (1.0 + num.norm()),
                "keyframe {which}, column {k}: {num} vs {}",
                analytic.column(k)
            );
        }
    }
}

/// An entry of a test point or pose: random, now and then a zero of either sign or NaN.
fn entry(rng: &mut ChaCha8Rng, scale: f64) -> f64 {
    match rng.random_range(0..12) {
        0 => 0.0,
        1 => -0.0,
        2 => f64::NAN,
        _ => rng.random_range(-1.0..1.0) * scale,
    }
}

/// `linearize_point` (in the tracks' fit) gives `linearize`'s residual and `∂e/∂p` bit
/// for bit, and `None` where it does, on seeded random poses, points and measurements
/// (zeros of both signs and NaN among them).
#[test]
fn the_point_part_is_the_linearisations_bit_for_bit() {
    use crate::window::residual::linearize_point;
    use swarmpose_vision::frontend::DisparityCorrection;
    let mut model = crate::refine::model::test_model(DisparityCorrection::from_coefficients([
        0.7, 1.9, -0.4, 0.3, 0.8,
    ]));
    let mut rng = ChaCha8Rng::seed_from_u64(34);
    let (mut some, mut none) = (0, 0);
    for trial in 0..20_000 {
        if trial == 10_000 {
            model.correction = DisparityCorrection::default();
        }
        let poses: Vec<Pose> = (0..3)
            .map(|_| Pose {
                rot: *Rotation3::from_euler_angles(
                    entry(&mut rng, 0.2),
                    entry(&mut rng, 0.2),
                    entry(&mut rng, 0.2),
                )
                .matrix(),
                trans: Vector3::from_fn(|_, _| entry(&mut rng, 10.0)),
            })
            .collect();
        let mut rel = Vec::new();
        relative_poses(&poses, &mut rel);
        let p = Vector3::new(
            entry(&mut rng, 0.8),
            entry(&mut rng, 0.4),
            entry(&mut rng, 0.2).abs(),
        );
        let z = StereoObservation {
            u: rng.random_range(0.0..1240.0),
            v: rng.random_range(0.0..370.0),
            d: entry(&mut rng, 60.0),
        };
        let (anchor, slot) = (rng.random_range(0..3), rng.random_range(0..3));
        let want = linearize(&model, (&rel, 3), anchor, slot, &p, &z);
        let got = linearize_point(&model, (&rel, 3), anchor, slot, &p, &z);
        match (want, got) {
            (Some(w), Some((residual, d_point))) => {
                // NaN for NaN: Rust leaves the sign and payload of an arithmetic NaN
                // unspecified (the compiler may commute the operands of a product).
                let bits = |a: &[f64], b: &[f64]| {
                    a.iter()
                        .zip(b)
                        .all(|(x, y)| x.to_bits() == y.to_bits() || (x.is_nan() && y.is_nan()))
                };
                assert!(bits(w.residual.as_slice(), residual.as_slice()), "{trial}");
                assert!(bits(w.d_point.as_slice(), d_point.as_slice()), "{trial}");
                some += 1;
            }
            (None, None) => none += 1,
            _ => panic!("trial {trial}: one gave a linearisation, the other none"),
        }
    }
    assert!(some > 5_000 && none > 100, "{some} {none}");
}
