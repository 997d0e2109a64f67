//! Small fixed-size products of the solvers' normal equations, entry by entry with
//! exactly the arithmetic of the nalgebra expressions they replace (issue 34), but with
//! fewer operations: no transposed copies or temporaries, and a symmetric product
//! `aᵀ a w` computed on one triangle and mirrored.
//!
//! nalgebra's product of fixed-size matrices (`gemm` with `alpha = 1`, `beta = 0`)
//! accumulates `C[:, j] += A[:, k] B[k, j]` over `k` in order, so entry `(i, j)` of
//! `aᵀ b` (`a`, `b` with 3 rows) is `(a₀ᵢ b₀ⱼ + a₁ᵢ b₁ⱼ) + a₂ᵢ b₂ⱼ` (its `1 · x` and
//! `x + 1 · y` are exact, and a floating sum or product of two terms does not depend on
//! their order). Entry `(j, i)` of `aᵀ a` is the same sum of the same products, so it
//! is the same number bit for bit: mirroring one triangle changes nothing. A scalar
//! factor (`… * w`) multiplies each entry afterwards, as here. The tests compare
//! `to_bits()` against the nalgebra expressions on random input.

use nalgebra::SMatrix;

/// Entry `(i, j)` of `aᵀ b` summed as nalgebra's `a.transpose() * b` sums it, from the
/// columns `a` and `b` (nalgebra's column-major storage).
#[inline(always)]
fn tdot(a: &[f64; 3], b: &[f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// Entry `(i, j)` of `t b` (`t` with 3 columns, `b` with 3 rows) summed as nalgebra's
/// `t * b` sums it, from `t`'s columns and `b`'s column `j`.
#[inline(always)]
fn dot<const R: usize>(t: &[[f64; R]; 3], i: usize, b: &[f64; 3]) -> f64 {
    t[0][i] * b[0] + t[1][i] * b[1] + t[2][i] * b[2]
}

/// `acc += aᵀ a w`, the same bits as `*acc += a.transpose() * a * w` (one triangle of
/// the symmetric product computed and mirrored).
#[inline(always)]
pub(crate) fn add_gram<const C: usize>(
    acc: &mut SMatrix<f64, C, C>,
    a: &SMatrix<f64, 3, C>,
    w: f64,
) {
    let (a, acc) = (&a.data.0, &mut acc.data.0);
    for j in 0..C {
        for i in 0..j {
            let v = tdot(&a[i], &a[j]) * w;
            acc[j][i] += v;
            acc[i][j] += v;
        }
        acc[j][j] += tdot(&a[j], &a[j]) * w;
    }
}

/// `aᵀ a w`, the same bits as `a.transpose() * a * w` (one triangle computed and
/// mirrored).
#[inline(always)]
pub(crate) fn gram<const C: usize>(a: &SMatrix<f64, 3, C>, w: f64) -> SMatrix<f64, C, C> {
    let mut out = SMatrix::<f64, C, C>::zeros();
    let (a, o) = (&a.data.0, &mut out.data.0);
    for j in 0..C {
        for i in 0..j {
            let v = tdot(&a[i], &a[j]) * w;
            o[j][i] = v;
            o[i][j] = v;
        }
        o[j][j] = tdot(&a[j], &a[j]) * w;
    }
    out
}

/// `acc += aᵀ b w`, the same bits as `*acc += a.transpose() * b * w`.
#[inline(always)]
pub(crate) fn add_cross<const C1: usize, const C2: usize>(
    acc: &mut SMatrix<f64, C1, C2>,
    a: &SMatrix<f64, 3, C1>,
    b: &SMatrix<f64, 3, C2>,
    w: f64,
) {
    let (a, b, acc) = (&a.data.0, &b.data.0, &mut acc.data.0);
    for j in 0..C2 {
        for i in 0..C1 {
            acc[j][i] += tdot(&a[i], &b[j]) * w;
        }
    }
}

/// `aᵀ b w`, the same bits as `a.transpose() * b * w`.
#[inline(always)]
pub(crate) fn cross<const C1: usize, const C2: usize>(
    a: &SMatrix<f64, 3, C1>,
    b: &SMatrix<f64, 3, C2>,
    w: f64,
) -> SMatrix<f64, C1, C2> {
    // Written, not added to zeros: `0.0 + -0.0` would turn a negative zero positive.
    let mut out = SMatrix::<f64, C1, C2>::zeros();
    let (a, b, o) = (&a.data.0, &b.data.0, &mut out.data.0);
    for j in 0..C2 {
        for i in 0..C1 {
            o[j][i] = tdot(&a[i], &b[j]) * w;
        }
    }
    out
}

/// `aᵀ b`, the same bits as `a.transpose() * b`.
#[inline(always)]
pub(crate) fn tr_mul<const C1: usize, const C2: usize>(
    a: &SMatrix<f64, 3, C1>,
    b: &SMatrix<f64, 3, C2>,
) -> SMatrix<f64, C1, C2> {
    let mut out = SMatrix::<f64, C1, C2>::zeros();
    let (a, b, o) = (&a.data.0, &b.data.0, &mut out.data.0);
    for j in 0..C2 {
        for i in 0..C1 {
            o[j][i] = tdot(&a[i], &b[j]);
        }
    }
    out
}

/// `t b`, the same bits as `t * b` (each entry written, not added to zeros).
// The index form, as in `accumulate_product`.
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(crate) fn mul<const R: usize, const C: usize>(
    t: &SMatrix<f64, R, 3>,
    b: &SMatrix<f64, 3, C>,
) -> SMatrix<f64, R, C> {
    let mut out = SMatrix::<f64, R, C>::zeros();
    let (t, b, o) = (&t.data.0, &b.data.0, &mut out.data.0);
    for j in 0..C {
        for i in 0..R {
            o[j][i] = dot(t, i, &b[j]);
        }
    }
    out
}

/// `a x` for `a` with `K` columns and `x` given by its `K` entries, the same bits as
/// nalgebra's `a * x` (its matrix-vector product sums `a[(i, k)] x[k]` over `k` in
/// order, the first term written, not added to zero).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
pub(crate) fn mul_vec<const R: usize, const K: usize>(
    a: &SMatrix<f64, R, K>,
    x: &[f64; K],
) -> SMatrix<f64, R, 1> {
    let mut out = SMatrix::<f64, R, 1>::zeros();
    let (a, o) = (&a.data.0, &mut out.data.0[0]);
    for i in 0..R {
        let mut sum = a[0][i] * x[0];
        for k in 1..K {
            sum += a[k][i] * x[k];
        }
        o[i] = sum;
    }
    out
}

/// `acc += t b`, the same bits as `*acc += t * b`.
#[inline(always)]
pub(crate) fn add_product<const R: usize, const C: usize>(
    acc: &mut SMatrix<f64, R, C>,
    t: &SMatrix<f64, R, 3>,
    b: &SMatrix<f64, 3, C>,
) {
    accumulate_product::<R, C, false>(acc, t, b);
}

/// `acc -= t b`, the same bits as `*acc -= t * b`.
#[inline(always)]
pub(crate) fn sub_product<const R: usize, const C: usize>(
    acc: &mut SMatrix<f64, R, C>,
    t: &SMatrix<f64, R, 3>,
    b: &SMatrix<f64, 3, C>,
) {
    accumulate_product::<R, C, true>(acc, t, b);
}

/// [`add_product`], or [`sub_product`] when `SUBTRACT`.
// The index form: `iter_mut().enumerate()` compiled to a fifth more instructions in the
// window's system (callgrind, issue 34).
#[allow(clippy::needless_range_loop)]
#[inline(always)]
fn accumulate_product<const R: usize, const C: usize, const SUBTRACT: bool>(
    acc: &mut SMatrix<f64, R, C>,
    t: &SMatrix<f64, R, 3>,
    b: &SMatrix<f64, 3, C>,
) {
    let (t, b, acc) = (&t.data.0, &b.data.0, &mut acc.data.0);
    for j in 0..C {
        for i in 0..R {
            let x = dot(t, i, &b[j]);
            if SUBTRACT {
                acc[j][i] -= x;
            } else {
                acc[j][i] += x;
            }
        }
    }
}

#[cfg(test)]
#[path = "products_tests.rs"]
pub(crate) mod tests;
