//! The rows of a stereo pair as evidence of the right camera's rotation.
//!
//! A rotation `ω = (φ, ψ, θ)` (pitch, yaw, roll) of the right camera against the
//! rectification moves each right image point vertically by
//! `f (φ (1 + y²) − θ x − ψ x y)` (`x`, `y` the right point's normalised coordinates;
//! [`DisparityCorrection`]'s module documentation), which the stereo matcher measures as
//! the row offset of every match (`StereoFrame::row_offsets_px` of the vision crate). A least-squares fit
//!
//! ```text
//! dy = c₀ + c₁ x + c₂ y + c₃ x y + c₄ y²
//! ```
//!
//! reads the rotation off a single frame: `f ψ = −c₃`, `f θ = −c₁`, `f φ = c₄` (`c₀`
//! also holds a vertical principal point offset and `c₂` a vertical focal length
//! mismatch: nuisances that do not move disparities). Only matches that a tracked motion
//! confirmed are used: a wrong stereo match, found along the same row, would pull every
//! term towards 0. The same rotation moves the right
//! points horizontally, which is the disparity error: yaw `−f ψ (1 + x²)`, roll `f θ y`,
//! pitch `f φ x y`. The fit's normal equations are summed over frames (a fixed-size
//! state), separately for two folds of the matches (alternate vertical stripes), so
//! that each rotation term is used only when the held-out fold confirms it.

use nalgebra::{SMatrix, SVector};
use swarmpose_vision::frontend::DisparityCorrection;
use swarmpose_vision::stereo::RectifiedStereo;

use super::subset::{Terms, solve_on, sub_matrix};

/// Terms of the row-offset fit: `[1, x, y, x y, y², x², x² y, y³]`.
const R: usize = 8;
/// Row offsets larger than this are not used, pixels (wrong stereo matches).
const MAX_ROW_OFFSET_PX: f32 = 1.5;

type MatrixR = SMatrix<f64, R, R>;
type VectorR = SVector<f64, R>;

/// The rotation terms the rows can show, as indices into the fit.
pub(crate) const YAW: usize = 3;
/// Roll: the `x` term.
pub(crate) const ROLL: usize = 1;
/// Pitch: the `y²` term.
pub(crate) const PITCH: usize = 4;
/// The `y` term: a right camera whose focal length is `Δf` pixels long scales its rows
/// by `Δf y` (and its columns by `Δf x`, the disparity's linear term).
pub(crate) const VERTICAL_SCALE: usize = 2;
/// Nuisance terms, always fitted: constant, `y` (a vertical focal length mismatch), and
/// `x²`, `x² y`, `y³` (lens distortion left by the rectification).
const NUISANCE: [usize; 5] = [0, 2, 5, 6, 7];

/// Normal equations of the fit over one fold.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Normal {
    a: MatrixR,
    b: VectorR,
    yy: f64,
    n: usize,
}

impl Default for Normal {
    fn default() -> Self {
        Self {
            a: MatrixR::zeros(),
            b: VectorR::zeros(),
            yy: 0.0,
            n: 0,
        }
    }
}

impl Normal {
    /// Sum of squared residuals at `c`.
    fn rss(&self, c: &VectorR) -> f64 {
        (self.yy - 2.0 * self.b.dot(c) + (c.transpose() * self.a * c)[0]).max(0.0)
    }

    fn plus(&self, o: &Self) -> Self {
        Self {
            a: self.a + o.a,
            b: self.b + o.b,
            yy: self.yy + o.yy,
            n: self.n + o.n,
        }
    }

    /// Covariance of the rotation terms among `terms` (`f ψ`, `f θ`, `f φ` in the signs of
    /// [`RowDecision::rotation_px`]) fitted as `c`: the residual variance times the
    /// inverse of the normal equations over `terms`; zero for the terms not fitted.
    fn rotation_covariance(&self, terms: &[usize], c: &VectorR) -> [[f64; 3]; 3] {
        let mut out = [[0.0; 3]; 3];
        let n = terms.len();
        let dof = self.n.saturating_sub(n).max(1) as f64;
        let variance = self.rss(c) / dof;
        let Some(inv) = sub_matrix(&self.a, terms).cholesky().map(|c| c.inverse()) else {
            return out;
        };
        let rotation = [(YAW, -1.0), (ROLL, -1.0), (PITCH, 1.0)];
        for (r1, &(k1, s1)) in rotation.iter().enumerate() {
            for (r2, &(k2, s2)) in rotation.iter().enumerate() {
                if let (Some(i), Some(j)) = (
                    terms.iter().position(|&t| t == k1),
                    terms.iter().position(|&t| t == k2),
                ) {
                    let v = s1 * s2 * variance * inv[(i, j)];
                    out[r1][r2] = if v.is_finite() { v } else { 0.0 };
                }
            }
        }
        out
    }

    /// Least squares over the terms in `terms` (the others 0).
    fn fit(&self, terms: &[usize]) -> VectorR {
        let mut out = VectorR::zeros();
        if let Some(x) = solve_on(&self.a, &self.b, terms) {
            for (&k, x) in terms.iter().zip(x.iter()) {
                out[k] = *x;
            }
        }
        out
    }
}

/// The rotation terms the rows support, and the correction they imply.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RowDecision {
    /// Yaw supported.
    pub yaw: bool,
    /// Roll supported.
    pub roll: bool,
    /// Pitch supported.
    pub pitch: bool,
    /// Fitted `f ψ`, `f θ`, `f φ` (pixels), whether supported or not.
    pub rotation_px: [f64; 3],
    /// Held-out score of the terms chosen, χ² units relative to none (lower is better).
    pub score: f64,
    /// The fraction of the supported terms applied, from their held-out score
    /// ([`super::applied_fraction`]): 0 for terms chosen by a hair, 1 from one margin
    /// beyond; 0 when none is supported.
    pub weight: f64,
    /// The rows' `y` term, pixels (`Δf` of a right camera whose focal length is `Δf`
    /// pixels long; also a vertical focal length mismatch of the rectification), fitted
    /// with the terms supported.
    pub vertical_scale_px: f64,
    /// Whether the held-out folds support the `y` term: leaving it out raises the
    /// held-out score by more than the margin. Reported, not used: a right camera's
    /// focal length would show here as well as in the disparity's linear term, but
    /// requiring it removed the linear term on Karlsruhe where the INS favours it
    /// (docs/self-calibration.md).
    pub vertical_scale: bool,
    /// Row offsets used, over all frames.
    pub measurements: usize,
    /// Covariance of the supported terms of `rotation_px` (pixels², zero for the others):
    /// the residual variance times the inverse of the normal equations over the terms
    /// fitted.
    pub rotation_covariance: [[f64; 3]; 3],
}

impl RowDecision {
    /// The disparity correction of the supported rotation terms, applied with
    /// [`RowDecision::weight`].
    #[must_use]
    pub fn correction(&self) -> DisparityCorrection {
        let [fpsi, ftheta, fphi] = self.rotation_px.map(|r| r * self.weight);
        let mut c = DisparityCorrection::default();
        if self.yaw {
            c.offset_px -= fpsi;
            c.quadratic_px -= fpsi;
        }
        if self.roll {
            c.linear_y_px += ftheta;
        }
        if self.pitch {
            c.cross_xy_px += fphi;
        }
        c
    }
}

/// Row-offset evidence summed over frames.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct RowEvidence {
    folds: [Normal; 2],
}

impl RowEvidence {
    /// Adds row offsets: `(u, v, d, dy)` of stereo matches (left pixel, disparity and row
    /// offset, pixels); `stripe_px` is the width of the fold stripes.
    pub fn add(
        &mut self,
        samples: impl IntoIterator<Item = (f64, f64, f64, f32)>,
        rig: &RectifiedStereo,
        stripe_px: f64,
    ) {
        for (u, v, d, dy) in samples {
            if !(dy.is_finite() && dy.abs() <= MAX_ROW_OFFSET_PX) {
                continue;
            }
            let x = (u - d - rig.cx) / rig.fx;
            let y = (v - rig.cy) / rig.fy;
            let phi = VectorR::from([1.0, x, y, x * y, y * y, x * x, x * x * y, y * y * y]);
            let fold = &mut self.folds[((u / stripe_px).floor().max(0.0) as u64 % 2) as usize];
            let dy = f64::from(dy);
            fold.a += phi * phi.transpose();
            fold.b += phi * dy;
            fold.yy += dy * dy;
            fold.n += 1;
        }
    }

    /// Forward selection of the rotation terms (nuisance terms always in): each added
    /// while it lowers the held-out score (fit on one fold, residuals on the other, in
    /// units of the residual variance) by more than `margin`.
    #[must_use]
    pub fn decide(&self, margin: f64) -> RowDecision {
        let all = self.folds[0].plus(&self.folds[1]);
        let full: [usize; R] = std::array::from_fn(|k| k);
        let mut decision = RowDecision {
            measurements: all.n,
            ..RowDecision::default()
        };
        if self.folds.iter().any(|f| f.n < 2 * R) {
            return decision;
        }
        let c_full = all.fit(&full);
        let variance = all.rss(&c_full) / (all.n.saturating_sub(R).max(1)) as f64;
        if !(variance.is_finite() && variance > 0.0) {
            return decision;
        }
        decision.rotation_px = [-c_full[YAW], -c_full[ROLL], c_full[PITCH]];
        let score = |terms: &[usize]| {
            let [f0, f1] = &self.folds;
            (f0.rss(&f1.fit(terms)) + f1.rss(&f0.fit(terms))) / variance
        };
        // On the stack: a copy for every candidate scored (issue 34).
        let mut terms = Terms::<R>::of(&NUISANCE);
        let base = score(&terms);
        let mut best = 0.0;
        loop {
            let candidate = [YAW, ROLL, PITCH]
                .into_iter()
                .filter(|k| !terms.contains(k))
                .map(|k| (k, score(&terms.with(k)) - base))
                .min_by(|a, b| a.1.total_cmp(&b.1));
            match candidate {
                Some((k, s)) if s < best - margin => {
                    terms.push(k);
                    best = s;
                }
                _ => break,
            }
        }
        decision.yaw = terms.contains(&YAW);
        decision.roll = terms.contains(&ROLL);
        decision.pitch = terms.contains(&PITCH);
        decision.score = best;
        decision.weight = super::applied_fraction(best, terms.len() - NUISANCE.len(), margin);
        // The supported terms refitted without the unsupported ones.
        let c = all.fit(&terms);
        let mut without = Terms::<R>::new();
        for &k in terms.iter().filter(|&&k| k != VERTICAL_SCALE) {
            without.push(k);
        }
        decision.vertical_scale = score(&without) - score(&terms) > margin;
        decision.vertical_scale_px = c[VERTICAL_SCALE];
        decision.rotation_covariance = all.rotation_covariance(&terms, &c);
        decision.rotation_px = [
            if decision.yaw { -c[YAW] } else { -c_full[YAW] },
            if decision.roll {
                -c[ROLL]
            } else {
                -c_full[ROLL]
            },
            if decision.pitch {
                c[PITCH]
            } else {
                c_full[PITCH]
            },
        ];
        decision
    }
}
