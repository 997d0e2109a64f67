//! Least squares over some of the coefficients of a quadratic, the others held: what the
//! fits on a calibration base ([`super::fit`]) and the row-offset fit ([`super::rows`])
//! share.

use nalgebra::{SMatrix, SVector};

/// `a` over the coefficients `idx`, in that order, in the top-left corner; the identity
/// elsewhere (so that the matrix is invertible exactly when that corner is).
pub(super) fn sub_matrix<const D: usize>(
    a: &SMatrix<f64, D, D>,
    idx: &[usize],
) -> SMatrix<f64, D, D> {
    let mut s = SMatrix::identity();
    for (i, &ki) in idx.iter().enumerate() {
        for (j, &kj) in idx.iter().enumerate() {
            s[(i, j)] = a[(ki, kj)];
        }
    }
    s
}

/// The minimiser of `½ zᵀ A z − bᵀ z` over the coefficients `idx` (the others 0): `z[i]`
/// is coefficient `idx[i]`. A ridge of `1e-12` times the largest diagonal of `A` there
/// keeps a rank-deficient `A` solvable. `None` when `idx` is empty, that diagonal is 0,
/// or `A` is not positive definite there.
pub(super) fn solve_on<const D: usize>(
    a: &SMatrix<f64, D, D>,
    b: &SVector<f64, D>,
    idx: &[usize],
) -> Option<SVector<f64, D>> {
    let n = idx.len();
    let mut sa = sub_matrix(a, idx);
    let mut sb = SVector::<f64, D>::zeros();
    for (i, &ki) in idx.iter().enumerate() {
        sb[i] = b[ki];
    }
    let scale = (0..n).map(|i| sa[(i, i)].abs()).fold(0.0, f64::max);
    if n == 0 || scale <= 0.0 {
        return None;
    }
    for i in 0..n {
        sa[(i, i)] += 1e-12 * scale;
    }
    sa.cholesky().map(|chol| chol.solve(&sb))
}
