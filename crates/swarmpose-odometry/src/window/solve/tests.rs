//! Tests of the window's bundle adjustment.

use super::*;
use crate::refine::Prepared;
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
    let j = linearize(&Prepared::new(&model), (&rel, 3), anchor, slot, &p, &z).expect("in view");
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
                linearize(&Prepared::new(&model), (&rel, 3), anchor, slot, &p, &z)
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
        let want = linearize(&Prepared::new(&model), (&rel, 3), anchor, slot, &p, &z);
        let got = linearize_point(&Prepared::new(&model), (&rel, 3), anchor, slot, &p, &z);
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

/// The window's refinement as dispatched (compiled for the CPU's best instruction set,
/// AVX2 where there is one) gives its baseline compilation's poses, report and buffers bit
/// for bit (`{:?}` prints every bit of a number but a NaN's sign and payload, which Rust
/// leaves unspecified), on seeded windows of 2 to 6 keyframes whose measurements are noisy
/// projections, now and then NaN or a zero of either sign; marginalising builds the same.
#[test]
fn the_dispatched_window_is_the_baseline_bit_for_bit() {
    use crate::window::{Keyframe, WindowConfig};
    use swarmpose_vision::frontend::DisparityCorrection;
    let model = crate::refine::model::test_model(DisparityCorrection::from_coefficients([
        0.7, 1.9, -0.4, 0.3, 0.8,
    ]));
    let mut rng = ChaCha8Rng::seed_from_u64(35);
    let config = WindowConfig {
        max_iterations: 4,
        ..WindowConfig::default()
    };
    let calibration = MatrixK::identity() * 0.01;
    let mut refined = 0;
    for trial in 0..40 {
        let mut frames = random_window(&model, &mut rng);
        let mut base = frames.clone();
        let (mut ws, mut ws_base) = (Workspace::default(), Workspace::default());
        let got = refine_window(&model, &calibration, &config, &mut frames, None, &mut ws);
        let want = swarmpose_vision::simd::baseline(|| {
            refine_window(&model, &calibration, &config, &mut base, None, &mut ws_base)
        });
        let poses = |f: &[Keyframe]| f.iter().map(|k| k.pose_cw).collect::<Vec<_>>();
        assert_eq!(
            format!("{got:?} {:?} {ws:?}", poses(&frames)),
            format!("{want:?} {:?} {ws_base:?}", poses(&base)),
            "trial {trial}"
        );
        refined += usize::from(got.is_some());
        // The marginalisation's system, points at their anchors: built the same.
        let poses: Vec<Pose> = frames.iter().map(|f| Pose::of(&f.pose_cw)).collect();
        let (mut sc, mut sc_base) = (Scratch::default(), Scratch::default());
        let got = linearised_system(&model, 2.5, &poses, &ws.tracks, &mut sc);
        let want = swarmpose_vision::simd::baseline(|| {
            linearised_system(&model, 2.5, &poses, &ws.tracks, &mut sc_base)
        });
        assert_eq!(
            format!("{got:?} {sc:?}"),
            format!("{want:?} {sc_base:?}"),
            "{trial}"
        );
    }
    assert!(refined >= 20, "{refined} of 40 refined");
}

/// A seeded window of 2 to 6 keyframes for the dispatch test: noisy projections of 80
/// points, now and then a NaN or a zero of either sign, from poses off the truth.
fn random_window(
    model: &crate::refine::model::StereoModel,
    rng: &mut ChaCha8Rng,
) -> Vec<crate::window::Keyframe> {
    use crate::window::Keyframe;
    use nalgebra::{Isometry3, Point3};
    let n = rng.random_range(2..7);
    let points: Vec<Point3<f64>> = (0..80)
        .map(|_| {
            let z = rng.random_range(4.0..40.0);
            Point3::new(
                rng.random_range(-0.8..0.8) * z,
                rng.random_range(-0.25..0.25) * z,
                z,
            )
        })
        .collect();
    (0..n)
        .map(|k| {
            let truth = Isometry3::new(
                Vector3::new(0.0, 0.0, -0.8 * k as f64),
                Vector3::new(0.0, 0.01 * k as f64, 0.0),
            );
            let observations = points
                .iter()
                .enumerate()
                .filter_map(|(t, p)| {
                    let q = truth * p;
                    let mut z = StereoObservation {
                        u: model.rig.fx * q.x / q.z + model.rig.cx + rng.random_range(-0.5..0.5),
                        v: model.rig.fy * q.y / q.z + model.rig.cy + rng.random_range(-0.5..0.5),
                        d: model.rig.fx * model.rig.baseline_m / q.z,
                    };
                    match rng.random_range(0..60) {
                        0 => z.d = f64::NAN,
                        1 => z.u = 0.0,
                        2 => z.v = -0.0,
                        _ => {}
                    }
                    (q.z > 1.0 && rng.random_range(0..6) > 0).then_some((t as u32, z))
                })
                .collect();
            // The starting poses off the truth.
            let start = Isometry3::new(
                Vector3::from_fn(|_, _| rng.random_range(-0.05..0.05)),
                Vector3::from_fn(|_, _| rng.random_range(-0.003..0.003)),
            ) * truth;
            Keyframe {
                index: k,
                pose_cw: start,
                observations,
                keyframe: true,
            }
        })
        .collect()
}

/// The refinement's system with the blocks below the diagonal only ([`Blocks::Lower`])
/// has every entry of the whole one's ([`Blocks::Full`]) on and below the diagonal blocks
/// bit for bit, those above mirrored, and the same gradient, pose-calibration blocks,
/// costs and eliminated blocks; the Cholesky factors of both are the same bits (the
/// factorisation reads the lower triangle only), on seeded windows of 2 to 6 keyframes,
/// the first held fixed or not.
#[test]
fn the_lower_blocks_give_the_whole_systems_factor_bit_for_bit() {
    use swarmpose_vision::frontend::DisparityCorrection;
    let model = crate::refine::model::test_model(DisparityCorrection::from_coefficients([
        0.7, 1.9, -0.4, 0.3, 0.8,
    ]));
    let mut rng = ChaCha8Rng::seed_from_u64(37);
    let bits = |m: &[f64]| m.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
    let mut factored = 0;
    for trial in 0..60 {
        let frames = random_window(&model, &mut rng);
        let poses: Vec<Pose> = frames.iter().map(|f| Pose::of(&f.pose_cw)).collect();
        let (mut rel, mut tracks) = (Vec::new(), Tracks::default());
        tracks_of(
            &model,
            2.5,
            &frames,
            &poses,
            |_| true,
            &mut rel,
            &mut tracks,
        );
        let points: Vec<Vector3<f64>> = tracks.list.iter().map(|t| t.point).collect();
        for fixed in [0, 1] {
            let (mut full, mut lower) = (Scratch::default(), Scratch::default());
            let a = build(
                &model,
                2.5,
                (&poses, fixed, Blocks::Full),
                &tracks,
                &points,
                &mut full,
            );
            let b = build(
                &model,
                2.5,
                (&poses, fixed, Blocks::Lower),
                &tracks,
                &points,
                &mut lower,
            );
            assert_eq!(a, b, "trial {trial}");
            if a.is_none() {
                continue;
            }
            let n = full.s.nrows();
            for c in 0..n {
                for r in 0..n {
                    // The blocks above the diagonal mirrored; those on it whole.
                    let (i, j) = if r / 6 < c / 6 { (c, r) } else { (r, c) };
                    let want = full.s[(i, j)].to_bits();
                    assert_eq!(lower.s[(r, c)].to_bits(), want, "trial {trial} ({r}, {c})");
                }
            }
            // Everything but the upper blocks: the same bits.
            assert_eq!(
                all_but_upper_blocks(&full),
                all_but_upper_blocks(&lower),
                "trial {trial}"
            );
            let (f, l) = (full.s.clone().cholesky(), lower.s.clone().cholesky());
            assert_eq!(f.is_some(), l.is_some(), "trial {trial}");
            if let (Some(f), Some(l)) = (f, l) {
                assert_eq!(bits(f.l().as_slice()), bits(l.l().as_slice()), "{trial}");
                let (x, y) = (f.solve(&full.g), l.solve(&lower.g));
                assert_eq!(bits(x.as_slice()), bits(y.as_slice()), "{trial}");
                factored += 1;
            }
        }
    }
    assert!(factored >= 40, "{factored} factorised");
}

/// A [`Scratch`]'s contents but the blocks above the diagonal of its system, every bit
/// (`{:?}` prints them all).
fn all_but_upper_blocks(sc: &Scratch) -> String {
    let blocks = (0..sc.gradient.len())
        .flat_map(|v1| (0..=v1).map(move |v2| (v1, v2)))
        .map(|(v1, v2)| sc.blocks[v1 * sc.gradient.len() + v2])
        .collect::<Vec<_>>();
    format!(
        "{blocks:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?} {:?}",
        sc.g, sc.gradient, sc.pose_calibration, sc.chi2, sc.cost, sc.elim, sc.hpx, sc.hgx, sc.rel
    )
}
