//! The noise scale of a pair's measurements, taken from its residuals: the residuals'
//! variance factor assumes every measurement's error independent of every other's; real
//! errors are not (the same texture matched the same wrong way, a local bias of the
//! feature positions), and errors shared by the features of a region do not average out
//! over them. The cluster-robust ("sandwich") estimate of the score's covariance counts
//! them: the features are grouped into regions of the current image, each region's
//! contribution to the pose's score summed before it is squared, so errors shared within
//! a region add up as they do in the estimate.

use nalgebra::{Matrix6, Vector6};

/// Regions of the image per side: the features are cut into this many bands by column
/// (at quantiles of their columns), and each band into this many cells by row (at
/// quantiles of its rows), so that every region holds about as many features whatever
/// the image's size or the features' layout.
pub const REGIONS_PER_SIDE: usize = 4;

/// One feature's contribution to the pose's score `g = Σ rᵢ` (the gradient of half the
/// cost with the feature's point eliminated), at its position in the current image.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Score {
    /// Column in the current image, pixels.
    pub u: f64,
    /// Row in the current image, pixels.
    pub v: f64,
    /// `rᵢ = J_ξᵀ W eᵢ − H_ξp H_pp⁻¹ g_p` (whitened units).
    pub r: Vector6<f64>,
}

/// The variance factor of the pose from the regions' scores: `tr(S⁻¹ M) / 6` with
/// `M = C / (C − 1) Σ_c g_c g_cᵀ` over the `C` regions' summed scores `g_c` and `S⁻¹`
/// the inverse information `info_inv`; the sandwich `S⁻¹ M S⁻¹` is the covariance when
/// it is taken as `factor · S⁻¹` (1 for independent errors of the modelled size). `None`
/// with fewer than 2 features a region on average.
#[must_use]
pub fn cluster_factor(scores: &mut [Score], info_inv: &Matrix6<f64>) -> Option<f64> {
    let k = REGIONS_PER_SIDE;
    if scores.len() < 2 * k * k {
        return None;
    }
    // Unstable sorts allocate nothing (a stable sort takes a buffer); ties are broken by
    // the other coordinate, so the regions do not depend on the input's order.
    scores.sort_unstable_by(|a, b| a.u.total_cmp(&b.u).then(a.v.total_cmp(&b.v)));
    let mut m = Matrix6::zeros();
    let mut regions = 0usize;
    let n = scores.len();
    for band in 0..k {
        let cut = &mut scores[band * n / k..(band + 1) * n / k];
        cut.sort_unstable_by(|a, b| a.v.total_cmp(&b.v).then(a.u.total_cmp(&b.u)));
        let len = cut.len();
        for cell in 0..k {
            let g: Vector6<f64> = cut[cell * len / k..(cell + 1) * len / k]
                .iter()
                .map(|s| s.r)
                .sum();
            m += g * g.transpose();
            regions += 1;
        }
    }
    let c = regions as f64;
    let factor = (info_inv * m).trace() / 6.0 * c / (c - 1.0);
    factor.is_finite().then_some(factor)
}

/// The variance factor of a covariance `factor · S⁻¹`: the larger of the residuals'
/// `classic` one (`Σ w |e|² / dof`, which counts every measurement as independent) and
/// the regions' `cluster` one ([`cluster_factor`], which sees errors shared within a
/// region), so that the covariance is never made smaller than the residuals say.
#[must_use]
pub fn variance_factor(classic: f64, cluster: Option<f64>) -> f64 {
    cluster.map_or(classic, |c| c.max(classic))
}
