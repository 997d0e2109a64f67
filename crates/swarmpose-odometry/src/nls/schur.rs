//! Points eliminated by their Schur complements: each point `p` (3 parameters) is solved
//! out of the normal equations `[H_xx H_xp; H_px H_pp] [δx; δp] = −[g_x; g_p]`, leaving
//! the reduced system `(H_xx − H_xp H_pp⁻¹ H_px) δx = −(g_x − H_xp H_pp⁻¹ g_p)` in the
//! other variables `x`; after it is solved each point follows by back-substitution,
//! `δp = −H_pp⁻¹ (g_p + H_px δx)`. Both solvers keep each point's blocks in fixed-size
//! matrices, so eliminating `N` points costs `O(N)`.

use nalgebra::{Matrix3, SMatrix, Vector3};

/// `H_pp⁻¹` of a point, `None` when its block is singular.
pub(crate) fn point_inverse(hpp: &Matrix3<f64>) -> Option<Matrix3<f64>> {
    hpp.try_inverse()
}

/// `H_xp H_pp⁻¹` for a variable `x` of `C` parameters, from `H_px` (3 x `C`) and
/// `H_pp⁻¹`: the factor that the point's Schur complement applies to its blocks
/// (`H_xp H_pp⁻¹ H_py` subtracted from `H_xy`, `H_xp H_pp⁻¹ g_p` from `g_x`).
pub(crate) fn through_point<const C: usize>(
    h_px: &SMatrix<f64, 3, C>,
    pp_inv: &Matrix3<f64>,
) -> SMatrix<f64, C, 3> {
    // The same bits as `h_px.transpose() * pp_inv`, without the transposed copy.
    super::products::tr_mul(h_px, pp_inv)
}

/// The point `p` moved by its back-substituted step, `p − H_pp⁻¹ (g_p + H_px δx)`, with
/// `rhs = g_p + H_px δx`.
pub(crate) fn back_substitute(
    p: &Vector3<f64>,
    pp_inv: &Matrix3<f64>,
    rhs: &Vector3<f64>,
) -> Vector3<f64> {
    p - pp_inv * rhs
}
