//! A correction of the stereo calibration's disparities: a smooth function of the image
//! position whose terms are the first-order effects of the right camera's errors.
//!
//! A right camera whose principal point is off by `δ₀` pixels shifts every disparity by
//! `δ₀`. A small rotation `ω = (φ, ψ, θ)` (pitch, yaw, roll; radians, about the camera's
//! x right, y down, z forward axes) of the right camera against the rectification moves
//! the right image point of normalised coordinates `(x, y)` (the right camera's:
//! `x = (u_right − cx)/f`, `y = (v − cy)/f`) by, to first order,
//!
//! ```text
//! Δu = f (−ψ (1 + x²) + θ y + φ x y),   Δv = f (φ (1 + y²) − θ x − ψ x y),
//! ```
//!
//! and a focal length off by a factor `1 + ε` moves it by `f ε x`. The horizontal shift
//! is the disparity error (a measured disparity is short by `δ = Δu`); the vertical one
//! is seen directly as the rows of the two images not matching
//! (`crate::stereo::subpixel::row_offset`), which is how the rotation terms can be
//! measured in a single frame. Together:
//!
//! ```text
//! δ(x, y) = offset + quadratic x² + linear_x x + linear_y y + cross_xy x y,
//! offset = δ₀ − f ψ,  quadratic = −f ψ,  linear_x = f ε,  linear_y = f θ,  cross_xy = f φ,
//! ```
//!
//! and the point measured at disparity `d` is really at `p d / (d + δ)`. For a stereo
//! point `p = (X, Y, Z)` of a rig of baseline `b`, `x = (X − b) / Z` and `y = Y / Z`.

use nalgebra::{Matrix3, Point3};
use swarmpose_core::{Correspondences, PoseError};

use super::{FrameMatches, offset_jacobian};

/// Number of terms of a [`DisparityCorrection`].
pub const CORRECTION_TERMS: usize = 5;

/// Disparity correction, pixels, as a function of the normalised coordinates of the
/// right image point, `x = (u − d − cx)/fx`, `y = (v − cy)/fy` (left pixel `(u, v)`,
/// disparity `d`):
///
/// ```text
/// δ(x, y) = offset + quadratic x² + linear_x x + linear_y y + cross_xy x y
/// ```
///
/// Each term is the first-order effect of one error of the right camera against the
/// rectification (see the module documentation): a principal point (`offset`), a yaw
/// `ψ` (`offset` and `quadratic`, both `−f ψ`), a focal length (`linear_x`), a roll
/// (`linear_y`), a pitch (`cross_xy`). The default is no correction.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct DisparityCorrection {
    /// Constant term, pixels (principal point plus yaw).
    pub offset_px: f64,
    /// Coefficient of `x²`, pixels (`−f ψ` for a yaw `ψ` of the right camera).
    pub quadratic_px: f64,
    /// Coefficient of `x`, pixels (a focal length of the right camera that is off).
    pub linear_x_px: f64,
    /// Coefficient of `y`, pixels (a roll of the right camera).
    pub linear_y_px: f64,
    /// Coefficient of `x y`, pixels (a pitch of the right camera).
    pub cross_xy_px: f64,
}

impl DisparityCorrection {
    /// The names of the terms, in the order of [`DisparityCorrection::coefficients`].
    pub const TERM_NAMES: [&'static str; CORRECTION_TERMS] =
        ["offset", "quadratic", "linear_x", "linear_y", "cross_xy"];

    /// A constant offset, pixels.
    #[must_use]
    pub fn constant(offset_px: f64) -> Self {
        Self {
            offset_px,
            ..Self::default()
        }
    }

    /// The coefficients, pixels: offset, `x²`, `x`, `y`, `x y`.
    #[must_use]
    pub fn coefficients(&self) -> [f64; CORRECTION_TERMS] {
        [
            self.offset_px,
            self.quadratic_px,
            self.linear_x_px,
            self.linear_y_px,
            self.cross_xy_px,
        ]
    }

    /// The correction with these coefficients (order of
    /// [`DisparityCorrection::coefficients`]).
    #[must_use]
    pub fn from_coefficients(c: [f64; CORRECTION_TERMS]) -> Self {
        Self {
            offset_px: c[0],
            quadratic_px: c[1],
            linear_x_px: c[2],
            linear_y_px: c[3],
            cross_xy_px: c[4],
        }
    }

    /// The basis functions at the normalised coordinates `(x, y)`: `[1, x², x, y, x y]`.
    #[must_use]
    pub fn basis(x: f64, y: f64) -> [f64; CORRECTION_TERMS] {
        [1.0, x * x, x, y, x * y]
    }

    /// `δ` at the normalised coordinates `(x, y)`, pixels.
    #[must_use]
    pub fn at_normalised(&self, x: f64, y: f64) -> f64 {
        Self::basis(x, y)
            .iter()
            .zip(self.coefficients())
            .map(|(b, c)| b * c)
            .sum()
    }

    /// `∂δ/∂x` at `(x, y)`, pixels.
    #[must_use]
    pub fn d_dx(&self, x: f64, y: f64) -> f64 {
        2.0 * self.quadratic_px * x + self.linear_x_px + self.cross_xy_px * y
    }

    /// `∂δ/∂y` at `(x, y)`, pixels.
    #[must_use]
    pub fn d_dy(&self, x: f64) -> f64 {
        self.linear_y_px + self.cross_xy_px * x
    }

    /// `δ` for the point `p` (metres, left camera frame) of a rig of baseline
    /// `baseline_m`: `x = (X − b) / Z`, `y = Y / Z`.
    #[must_use]
    pub fn at(&self, p: &Point3<f64>, baseline_m: f64) -> f64 {
        if p.z.abs() > f64::EPSILON {
            self.at_normalised((p.x - baseline_m) / p.z, p.y / p.z)
        } else {
            self.offset_px
        }
    }

    /// True when every coefficient is 0.
    #[must_use]
    pub fn is_none(&self) -> bool {
        self.coefficients().iter().all(|c| *c == 0.0)
    }
}

impl std::fmt::Display for DisparityCorrection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:.3} px", self.offset_px)?;
        let terms = [
            (self.quadratic_px, "x²"),
            (self.linear_x_px, "x"),
            (self.linear_y_px, "y"),
            (self.cross_xy_px, "x y"),
        ];
        for (c, name) in terms {
            if c != 0.0 {
                let sign = if c < 0.0 { '-' } else { '+' };
                write!(f, " {sign} {:.3} px {name}", c.abs())?;
            }
        }
        Ok(())
    }
}

impl FrameMatches {
    /// The same matches with `correction` added to every disparity (for a rig of baseline
    /// `baseline_m`): each point `p` of disparity `d` becomes `p k` with
    /// `k = d / (d + δ(p))`, and its covariance
    /// `T Σ Tᵀ` with `T` of `offset_jacobian` (exact for a constant `δ`; the small
    /// change of `δ` across the pixel's own noise is neglected).
    ///
    /// # Errors
    /// [`PoseError::NonFinite`] if the correction makes a disparity non-positive.
    pub fn with_disparity_correction(
        &self,
        correction: DisparityCorrection,
        baseline_m: f64,
    ) -> Result<Self, PoseError> {
        let c = &self.correspondences;
        let factors = |points: &[Point3<f64>], d: &[f64]| -> Vec<f64> {
            points
                .iter()
                .zip(d)
                .map(|(p, &d)| d / (d + correction.at(p, baseline_m)))
                .collect()
        };
        let ks = factors(c.src(), &self.src_disparities_px);
        let kd = factors(c.dst(), &self.dst_disparities_px);
        if let Some(index) = ks
            .iter()
            .chain(&kd)
            .position(|k| !(k.is_finite() && *k > 0.0))
        {
            return Err(PoseError::NonFinite {
                index: index % c.len().max(1),
            });
        }
        let scaled = |points: &[Point3<f64>], k: &[f64]| -> Vec<Point3<f64>> {
            points
                .iter()
                .zip(k)
                .map(|(p, &k)| Point3::from(p.coords * k))
                .collect()
        };
        let moved = |m: &[Matrix3<f64>], points: &[Point3<f64>], k: &[f64]| -> Vec<Matrix3<f64>> {
            m.iter()
                .zip(points.iter().zip(k))
                .map(|(m, (p, &k))| {
                    let t = offset_jacobian(p, k);
                    t * m * t.transpose()
                })
                .collect()
        };
        let shifted = |d: &[f64], points: &[Point3<f64>]| -> Vec<f64> {
            d.iter()
                .zip(points)
                .map(|(&d, p)| d + correction.at(p, baseline_m))
                .collect()
        };
        Ok(Self {
            correspondences: Correspondences::new(scaled(c.src(), &ks), scaled(c.dst(), &kd))?,
            noise_sigma_m: self
                .noise_sigma_m
                .iter()
                .zip(ks.iter().zip(&kd))
                .map(|(&s, (&a, &b))| s * a.max(b).powi(2))
                .collect(),
            src_covariances: moved(&self.src_covariances, c.src(), &ks),
            dst_covariances: moved(&self.dst_covariances, c.dst(), &kd),
            src_disparities_px: shifted(&self.src_disparities_px, c.src()),
            dst_disparities_px: shifted(&self.dst_disparities_px, c.dst()),
            src_pixels: self.src_pixels.clone(),
            dst_pixels: self.dst_pixels.clone(),
            src_index: self.src_index.clone(),
            dst_index: self.dst_index.clone(),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn terms_add_up_and_print() {
        let c = DisparityCorrection {
            offset_px: 0.5,
            quadratic_px: 2.0,
            ..DisparityCorrection::default()
        };
        assert_eq!(c.at(&Point3::new(0.5, 3.0, 10.0), 0.5), 0.5);
        assert!((c.at(&Point3::new(8.5, 0.0, 10.0), 0.5) - (0.5 + 2.0 * 0.64)).abs() < 1e-12);
        assert_eq!(c.to_string(), "0.500 px + 2.000 px x²");
        assert_eq!(DisparityCorrection::constant(1.25).to_string(), "1.250 px");
        let all = DisparityCorrection::from_coefficients([1.0, -1.5, 0.25, -0.5, 2.0]);
        assert_eq!(
            all.to_string(),
            "1.000 px - 1.500 px x² + 0.250 px x - 0.500 px y + 2.000 px x y"
        );
        let (x, y) = (0.3, -0.2);
        let expected = 1.0 - 1.5 * x * x + 0.25 * x - 0.5 * y + 2.0 * x * y;
        assert!((all.at_normalised(x, y) - expected).abs() < 1e-12);
        let h = 1e-6;
        let dx = (all.at_normalised(x + h, y) - all.at_normalised(x - h, y)) / (2.0 * h);
        let dy = (all.at_normalised(x, y + h) - all.at_normalised(x, y - h)) / (2.0 * h);
        assert!((dx - all.d_dx(x, y)).abs() < 1e-6 && (dy - all.d_dy(x)).abs() < 1e-6);
        assert_eq!(
            DisparityCorrection::from_coefficients(all.coefficients()),
            all
        );
    }
}
