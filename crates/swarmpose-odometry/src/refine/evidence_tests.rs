//! [`Reduced`]'s products against the nalgebra expressions they replace, bit for bit.

use nalgebra::{SMatrix, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;
use crate::nls::products::tests::{random, same_bits};

/// The blocks as they were computed before issue 34 (nalgebra's expressions).
fn add_direct_nalgebra(
    r: &mut Reduced,
    w: f64,
    pose: &Matrix3x6,
    corr: &Matrix3xK,
    e: &Vector3<f64>,
) {
    r.pose_pose += pose.transpose() * pose * w;
    r.pose_correction += pose.transpose() * corr * w;
    r.correction_correction += corr.transpose() * corr * w;
    r.pose_gradient += pose.transpose() * e * w;
    r.correction_gradient += corr.transpose() * e * w;
}

fn eliminate_nalgebra(r: &mut Reduced, b: &PointBlocks) {
    let tp = b.pose.transpose() * b.pp_inv;
    let cp = b.correction.transpose() * b.pp_inv;
    r.pose_pose -= tp * b.pose;
    r.pose_correction -= tp * b.correction;
    r.correction_correction -= cp * b.correction;
    r.pose_gradient -= tp * b.gradient;
    r.correction_gradient -= cp * b.gradient;
}

fn same(a: &Reduced, b: &Reduced) -> bool {
    same_bits(&a.pose_pose, &b.pose_pose)
        && same_bits(&a.pose_correction, &b.pose_correction)
        && same_bits(&a.correction_correction, &b.correction_correction)
        && same_bits(&a.pose_gradient, &b.pose_gradient)
        && same_bits(&a.correction_gradient, &b.correction_gradient)
}

/// Zeros of either sign, or (now and then) random entries.
fn zero_or_random<const R: usize, const C: usize>(rng: &mut ChaCha8Rng) -> SMatrix<f64, R, C> {
    if rng.random_range(0..8) == 0 {
        random(rng)
    } else {
        SMatrix::from_fn(|_, _| {
            if rng.random_range(0..2) == 0 {
                0.0
            } else {
                -0.0
            }
        })
    }
}

fn random_reduced(rng: &mut ChaCha8Rng) -> Reduced {
    Reduced {
        pose_pose: random(rng),
        pose_correction: random(rng),
        correction_correction: random(rng),
        pose_gradient: random(rng),
        correction_gradient: random(rng),
    }
}

#[test]
fn add_direct_and_eliminate_are_nalgebras_bit_for_bit() {
    let mut rng = ChaCha8Rng::seed_from_u64(34);
    let mut skipped_zero_jacobians = 0;
    for trial in 0..20_000 {
        let mut got = random_reduced(&mut rng);
        // A fresh system, as each pair's starts, now and then.
        if trial % 5 == 0 {
            got = Reduced::default();
        }
        let mut want = got;
        // Mostly frame A's zero pose Jacobian, with now and then a factor not finite.
        let pose: Matrix3x6 = zero_or_random(&mut rng);
        let corr: Matrix3xK = random(&mut rng);
        let mut e: Vector3<f64> = random(&mut rng);
        let w = match rng.random_range(0..100) {
            0 => f64::INFINITY,
            1 => f64::NAN,
            _ => rng.random_range(0.0..1.0),
        };
        if rng.random_range(0..100) == 0 {
            e[1] = f64::NEG_INFINITY;
        }
        skipped_zero_jacobians +=
            usize::from(got.zero_pose_terms_change_nothing(w, &pose, &e, None));
        let mut got_pose = got;
        let mut want_pose = want;
        got.add_direct(w, &pose, &corr, &e);
        add_direct_nalgebra(&mut want, w, &pose, &corr, &e);
        got_pose.add_direct_pose(w, &pose, &e);
        want_pose.pose_pose += pose.transpose() * pose * w;
        want_pose.pose_gradient += pose.transpose() * e * w;
        assert!(same(&got, &want), "add_direct, trial {trial}");
        assert!(
            same(&got_pose, &want_pose),
            "add_direct_pose, trial {trial}"
        );

        let b = PointBlocks {
            pp_inv: random::<3, 3>(&mut rng),
            pose: random(&mut rng),
            correction: random(&mut rng),
            gradient: random(&mut rng),
        };
        got.eliminate(&b);
        eliminate_nalgebra(&mut want, &b);
        assert!(same(&got, &want), "eliminate, trial {trial}");
        got_pose.eliminate_pose(&b);
        want_pose.pose_pose -= b.pose.transpose() * b.pp_inv * b.pose;
        want_pose.pose_gradient -= b.pose.transpose() * b.pp_inv * b.gradient;
        assert!(same(&got_pose, &want_pose), "eliminate_pose, trial {trial}");
    }
    // Both ways were taken: skipped and summed.
    assert!(
        (1_000..19_000).contains(&skipped_zero_jacobians),
        "{skipped_zero_jacobians}"
    );
}

/// A negative zero in the blocks is where skipping zero terms would show: `−0 + +0` is
/// `+0`. The check refuses to skip then.
#[test]
fn a_negative_zero_block_entry_is_not_skipped() {
    let mut r = Reduced::default();
    r.pose_pose[(2, 3)] = -0.0;
    let (pose, e) = (Matrix3x6::zeros(), Vector3::new(1.0, -2.0, 3.0));
    assert!(!r.zero_pose_terms_change_nothing(0.5, &pose, &e, None));
    let mut want = r;
    want.pose_pose += pose.transpose() * pose * 0.5;
    r.add_direct_pose(0.5, &pose, &e);
    assert_eq!(want.pose_pose[(2, 3)].to_bits(), 0.0_f64.to_bits());
    assert!(same_bits(&r.pose_pose, &want.pose_pose));
}

/// Equations accumulated from zeros by `add_direct*` and `eliminate*` never hold a `−0`
/// (so the `_accumulated` forms skip the scan for one), and those forms give nalgebra's
/// bits: long seeded sequences of frame A's zero Jacobians, random ones, zeros of both
/// signs, infinities and NaN ([`random`]'s entries).
#[test]
fn accumulated_equations_hold_no_negative_zero_and_keep_the_bits() {
    let mut rng = ChaCha8Rng::seed_from_u64(3434);
    let mut skipped = 0;
    for trial in 0..400 {
        let (mut got, mut want) = (Reduced::default(), Reduced::default());
        let (mut got_pose, mut want_pose) = (Reduced::default(), Reduced::default());
        for _ in 0..50 {
            let pose: Matrix3x6 = zero_or_random(&mut rng);
            let corr: Matrix3xK = random(&mut rng);
            let e: Vector3<f64> = random(&mut rng);
            let w = match rng.random_range(0..50) {
                0 => f64::NAN,
                1 => -0.0,
                _ => rng.random_range(0.0..1.0),
            };
            skipped += usize::from(got_pose.zero_pose_terms_change_nothing(w, &pose, &e, None));
            got.add_direct_accumulated(w, &pose, &corr, &e);
            add_direct_nalgebra(&mut want, w, &pose, &corr, &e);
            got_pose.add_direct_pose_accumulated(w, &pose, &e);
            want_pose.pose_pose += pose.transpose() * pose * w;
            want_pose.pose_gradient += pose.transpose() * e * w;
            assert!(same(&got, &want), "add_direct_accumulated, trial {trial}");
            assert!(same(&got_pose, &want_pose), "pose only, trial {trial}");
            assert!(got.accumulated() && got_pose.accumulated(), "trial {trial}");
            if rng.random_range(0..3) == 0 {
                let b = PointBlocks {
                    pp_inv: random::<3, 3>(&mut rng),
                    pose: zero_or_random(&mut rng),
                    correction: random(&mut rng),
                    gradient: random(&mut rng),
                };
                got.eliminate(&b);
                eliminate_nalgebra(&mut want, &b);
                got_pose.eliminate_pose(&b);
                want_pose.pose_pose -= b.pose.transpose() * b.pp_inv * b.pose;
                want_pose.pose_gradient -= b.pose.transpose() * b.pp_inv * b.gradient;
                assert!(got.accumulated() && got_pose.accumulated(), "trial {trial}");
            }
        }
        assert!(
            same(&got, &want) && same(&got_pose, &want_pose),
            "trial {trial}"
        );
    }
    // The zero Jacobians were skipped often, and not always.
    assert!((2_000..19_000).contains(&skipped), "{skipped}");
}

/// The check that the `_accumulated` forms rely on sees a `−0` where there is one.
#[test]
fn a_negative_zero_is_not_accumulated() {
    let mut r = Reduced::default();
    assert!(r.accumulated());
    r.pose_correction[(5, 1)] = -0.0;
    assert!(!r.accumulated());
}

/// The same bits, or both NaN: Rust leaves a NaN's sign and payload unspecified (the
/// sum of two NaNs takes one operand's, which the compiler may order either way).
fn same_or_nan(a: &Reduced, b: &Reduced) -> bool {
    let bits = |x: &[f64], y: &[f64]| {
        x.iter()
            .zip(y)
            .all(|(p, q)| p.to_bits() == q.to_bits() || (p.is_nan() && q.is_nan()))
    };
    bits(a.pose_pose.as_slice(), b.pose_pose.as_slice())
        && bits(a.pose_correction.as_slice(), b.pose_correction.as_slice())
        && bits(
            a.correction_correction.as_slice(),
            b.correction_correction.as_slice(),
        )
        && bits(a.pose_gradient.as_slice(), b.pose_gradient.as_slice())
        && bits(
            a.correction_gradient.as_slice(),
            b.correction_gradient.as_slice(),
        )
}

/// The forms for frame A's zero pose Jacobian and for frame B's give the bits of
/// `add_direct_accumulated` and `add_direct_pose_accumulated` (and so nalgebra's): long
/// seeded sequences of zero and random Jacobians with zeros of both signs, and weights
/// now and then infinite or NaN.
#[test]
fn the_reference_and_current_forms_keep_the_bits() {
    let mut rng = ChaCha8Rng::seed_from_u64(3737);
    let mut reference_skips = 0;
    for trial in 0..400 {
        let (mut got, mut want) = (Reduced::default(), Reduced::default());
        let (mut got_pose, mut want_pose) = (Reduced::default(), Reduced::default());
        for _ in 0..50 {
            let in_reference = rng.random_range(0..2) == 0;
            let pose: Matrix3x6 = if in_reference {
                Matrix3x6::zeros()
            } else {
                zero_or_random(&mut rng)
            };
            let corr: Matrix3xK = random(&mut rng);
            let e: Vector3<f64> = random(&mut rng);
            let w = match rng.random_range(0..50) {
                0 => f64::NAN,
                1 => -0.0,
                2 => f64::INFINITY,
                _ => rng.random_range(0.0..1.0),
            };
            if in_reference {
                reference_skips +=
                    usize::from(got_pose.zero_pose_terms_change_nothing(w, &pose, &e, None));
                got.add_reference_accumulated(w, &pose, Some(&corr), &e);
                got_pose.add_reference_accumulated(w, &pose, None, &e);
            } else {
                got.add_current_accumulated(w, &pose, Some(&corr), &e);
                got_pose.add_current_accumulated(w, &pose, None, &e);
            }
            want.add_direct_accumulated(w, &pose, &corr, &e);
            want_pose.add_direct_pose_accumulated(w, &pose, &e);
            assert!(
                same_or_nan(&got, &want),
                "with the correction, trial {trial}"
            );
            assert!(
                same_or_nan(&got_pose, &want_pose),
                "pose only, trial {trial}"
            );
            if rng.random_range(0..3) == 0 {
                let b = PointBlocks {
                    pp_inv: random::<3, 3>(&mut rng),
                    pose: zero_or_random(&mut rng),
                    correction: random(&mut rng),
                    gradient: random(&mut rng),
                };
                for r in [&mut got, &mut want] {
                    r.eliminate(&b);
                }
                for r in [&mut got_pose, &mut want_pose] {
                    r.eliminate_pose(&b);
                }
            }
        }
        assert!(
            same_or_nan(&got, &want) && same_or_nan(&got_pose, &want_pose),
            "trial {trial}"
        );
    }
    // A's terms were skipped often, and not always.
    assert!(
        (1_000..9_900).contains(&reference_skips),
        "{reference_skips}"
    );
}
