//! The products of [`super`] against the nalgebra expressions they replace, bit for bit.

use nalgebra::SMatrix;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

/// A random entry over many magnitudes, with exact zeros of both signs now and then
/// (the sign of a zero sum is where a reordering would show).
fn entry(rng: &mut ChaCha8Rng) -> f64 {
    match rng.random_range(0..10) {
        0 => 0.0,
        1 => -0.0,
        2 => f64::from(rng.random_range(-3_i32..=3)),
        _ => {
            let m: f64 = rng.random_range(-1.0..1.0);
            m * 10f64.powi(rng.random_range(-6..=6))
        }
    }
}

pub(crate) fn random<const R: usize, const C: usize>(rng: &mut ChaCha8Rng) -> SMatrix<f64, R, C> {
    SMatrix::from_fn(|_, _| entry(rng))
}

pub(crate) fn same_bits<const R: usize, const C: usize>(
    got: &SMatrix<f64, R, C>,
    want: &SMatrix<f64, R, C>,
) -> bool {
    got.iter()
        .zip(want.iter())
        .all(|(a, b)| a.to_bits() == b.to_bits())
}

/// Runs `check` on 20 000 seeded random inputs; returns how many agreed bit for bit.
fn trials(mut check: impl FnMut(&mut ChaCha8Rng) -> bool) -> usize {
    let mut rng = ChaCha8Rng::seed_from_u64(34);
    (0..20_000).filter(|_| check(&mut rng)).count()
}

#[test]
fn gram_is_nalgebra_bit_for_bit() {
    let ok = trials(|rng| {
        let a: SMatrix<f64, 3, 6> = random(rng);
        let w = entry(rng);
        let mut acc: SMatrix<f64, 6, 6> = random(rng);
        let mut want = acc;
        want += a.transpose() * a * w;
        add_gram(&mut acc, &a, w);
        same_bits(&acc, &want) && same_bits(&gram(&a, w), &(a.transpose() * a * w))
    });
    assert_eq!(ok, 20_000);
}

#[test]
fn gram_of_three_columns_bit_for_bit() {
    let ok = trials(|rng| {
        let a: SMatrix<f64, 3, 3> = random(rng);
        let w = entry(rng);
        same_bits(&gram(&a, w), &(a.transpose() * a * w))
    });
    assert_eq!(ok, 20_000);
}

#[test]
fn cross_is_nalgebra_bit_for_bit() {
    let ok = trials(|rng| {
        let a: SMatrix<f64, 3, 6> = random(rng);
        let b: SMatrix<f64, 3, 4> = random(rng);
        let v: SMatrix<f64, 3, 1> = random(rng);
        let w = entry(rng);
        let mut acc: SMatrix<f64, 6, 4> = random(rng);
        let mut want = acc;
        want += a.transpose() * b * w;
        add_cross(&mut acc, &a, &b, w);
        same_bits(&acc, &want)
            && same_bits(&cross(&a, &b, w), &(a.transpose() * b * w))
            && same_bits(&cross(&a, &v, w), &(a.transpose() * v * w))
            && same_bits(&tr_mul(&a, &b), &(a.transpose() * b))
    });
    assert_eq!(ok, 20_000);
}

#[test]
fn sub_product_is_nalgebra_bit_for_bit() {
    let ok = trials(|rng| {
        let t: SMatrix<f64, 6, 3> = random(rng);
        let b: SMatrix<f64, 3, 6> = random(rng);
        let mut acc: SMatrix<f64, 6, 6> = random(rng);
        let mut want = acc;
        want -= t * b;
        sub_product(&mut acc, &t, &b);
        let mut acc2: SMatrix<f64, 6, 6> = random(rng);
        let mut want2 = acc2;
        want2 += t * b;
        add_product(&mut acc2, &t, &b);
        same_bits(&acc, &want) && same_bits(&acc2, &want2)
    });
    assert_eq!(ok, 20_000);
}

/// The window's products `t b` (3x3 by 3x6, 6x3 by 3x1, 3x3 by 3x1), NaN now and then
/// among the entries.
#[test]
fn mul_is_nalgebra_bit_for_bit() {
    let ok = trials(|rng| {
        let mut t: SMatrix<f64, 3, 3> = random(rng);
        let b: SMatrix<f64, 3, 6> = random(rng);
        let u: SMatrix<f64, 6, 3> = random(rng);
        let e: SMatrix<f64, 3, 1> = random(rng);
        if rng.random_range(0..16) == 0 {
            t[(rng.random_range(0..3), rng.random_range(0..3))] = f64::NAN;
        }
        // NaN for NaN: Rust leaves the sign and payload of an arithmetic NaN unspecified.
        let same = |got: &[f64], want: &[f64]| {
            got.iter()
                .zip(want)
                .all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()))
        };
        same(mul(&t, &b).as_slice(), (t * b).as_slice())
            && same(mul(&u, &e).as_slice(), (u * e).as_slice())
            && same(mul(&t, &e).as_slice(), (t * e).as_slice())
    });
    assert_eq!(ok, 20_000);
}

/// `a x` with 6 columns (the back-substitution's `H_pξ δξ`, the covariance's `Cᵀ r`),
/// NaN now and then among the entries.
#[test]
fn mul_vec_is_nalgebra_bit_for_bit() {
    let ok = trials(|rng| {
        let mut a: SMatrix<f64, 3, 6> = random(rng);
        let c: SMatrix<f64, 6, 6> = random(rng);
        let x: SMatrix<f64, 6, 1> = random(rng);
        if rng.random_range(0..16) == 0 {
            a[(rng.random_range(0..3), rng.random_range(0..6))] = f64::NAN;
        }
        let same = |got: &[f64], want: &[f64]| {
            got.iter()
                .zip(want)
                .all(|(a, b)| a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()))
        };
        let xs = &x.data.0[0];
        same(mul_vec(&a, xs).as_slice(), (a * x).as_slice())
            && same(
                mul_vec(&c.transpose(), xs).as_slice(),
                (c.transpose() * x).as_slice(),
            )
    });
    assert_eq!(ok, 20_000);
}

/// `fit_point`'s normal equations (`aᵀ a` and `aᵀ e` of its 3x3 Jacobians), NaN now and
/// then among the entries.
#[test]
fn three_by_three_tr_mul_is_nalgebra_bit_for_bit() {
    let ok = trials(|rng| {
        let mut a: SMatrix<f64, 3, 3> = random(rng);
        let e: SMatrix<f64, 3, 1> = random(rng);
        if rng.random_range(0..16) == 0 {
            a[(rng.random_range(0..3), rng.random_range(0..3))] = f64::NAN;
        }
        same_bits(&tr_mul(&a, &a), &(a.transpose() * a))
            && same_bits(&tr_mul(&a, &e), &(a.transpose() * e))
    });
    assert_eq!(ok, 20_000);
}

/// The check itself can fail: a reassociated sum differs from nalgebra's in some bits.
#[test]
fn a_reassociated_sum_is_caught() {
    let ok = trials(|rng| {
        let a: SMatrix<f64, 3, 6> = random(rng);
        let other = SMatrix::<f64, 6, 6>::from_fn(|i, j| {
            a[(0, i)] * a[(0, j)] + (a[(1, i)] * a[(1, j)] + a[(2, i)] * a[(2, j)])
        });
        same_bits(&other, &(a.transpose() * a))
    });
    assert!(ok < 20_000, "{ok}");
}
