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

/// A short list of distinct coefficient indices below `N`, kept on the stack (the
/// selections of [`super::rows`] and [`super::SelfCalibration`] copied one for every
/// candidate they score: an allocation each as a `Vec`, issue 34).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Terms<const N: usize> {
    idx: [usize; N],
    len: usize,
}

impl<const N: usize> Terms<N> {
    /// No index.
    pub(super) const fn new() -> Self {
        Self {
            idx: [0; N],
            len: 0,
        }
    }

    /// The indices of `idx`, in that order (as many as fit).
    pub(super) fn of(idx: &[usize]) -> Self {
        let mut t = Self::new();
        for &k in idx {
            t.push(k);
        }
        t
    }

    /// `self` with `k` added at the end.
    #[must_use]
    pub(super) fn with(mut self, k: usize) -> Self {
        self.push(k);
        self
    }

    /// Adds `k` at the end. The lists hold distinct indices below `N`, so there is room;
    /// were there none, `k` would be left out.
    pub(super) fn push(&mut self, k: usize) {
        debug_assert!(self.len < N, "more than {N} terms");
        if let Some(slot) = self.idx.get_mut(self.len) {
            *slot = k;
            self.len += 1;
        }
    }
}

impl<const N: usize> std::ops::Deref for Terms<N> {
    type Target = [usize];

    fn deref(&self) -> &[usize] {
        &self.idx[..self.len]
    }
}

#[cfg(test)]
mod tests {
    use super::Terms;

    #[test]
    fn terms_keep_their_order() {
        let t = Terms::<4>::of(&[3, 1]);
        assert_eq!(&*t, &[3, 1]);
        let u = t.with(0);
        assert_eq!(&*u, &[3, 1, 0]);
        assert_eq!(&*t, &[3, 1], "a copy");
        assert!(u.contains(&0) && !t.contains(&0));
        assert_eq!(u.len(), 3);
        assert!(Terms::<2>::new().is_empty());
    }
}
