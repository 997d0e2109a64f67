//! A correction of the stereo calibration's disparities: a constant offset plus a term
//! quadratic in the image column.
//!
//! A right camera whose principal point is off by `δ₀` pixels shifts every disparity by
//! `δ₀`. A small yaw `ψ` (radians) of the right camera against the rectification shifts
//! the right column of a ray at `x = (u - cx) / f` by `f (tan(atan x + ψ) - x)
//! ≈ f ψ (1 + x²)`. Together:
//!
//! ```text
//! δ(x) = offset_px + quadratic_px · x²,   offset_px = δ₀ + f ψ,   quadratic_px = f ψ,
//! ```
//!
//! and the point measured at disparity `d` is really at `p d / (d + δ(x))`. For a stereo
//! point `p = (X, Y, Z)`, `x = X / Z`, so the correction needs no calibration.

use nalgebra::{Matrix3, Point3};
use swarmpose_core::{Correspondences, PoseError};

use super::{FrameMatches, offset_jacobian};

/// Disparity correction `δ(x) = offset_px + quadratic_px · x²`, pixels, for the image
/// column `x = (u - cx) / f` (see the module documentation). The default is no
/// correction.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct DisparityCorrection {
    /// Correction at the image centre, pixels (principal point plus yaw).
    pub offset_px: f64,
    /// Growth towards the left and right edges, pixels per unit `x²` (`f ψ` for a yaw
    /// `ψ` of the right camera).
    pub quadratic_px: f64,
}

impl DisparityCorrection {
    /// A constant offset, pixels.
    #[must_use]
    pub fn constant(offset_px: f64) -> Self {
        Self {
            offset_px,
            quadratic_px: 0.0,
        }
    }

    /// `δ` for the point `p` (metres, camera frame): `x = X / Z`.
    #[must_use]
    pub fn at(&self, p: &Point3<f64>) -> f64 {
        let x = if p.z.abs() > f64::EPSILON {
            p.x / p.z
        } else {
            0.0
        };
        self.offset_px + self.quadratic_px * x * x
    }
}

impl std::fmt::Display for DisparityCorrection {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.quadratic_px == 0.0 {
            write!(f, "{:.3} px", self.offset_px)
        } else {
            let sign = if self.quadratic_px < 0.0 { '-' } else { '+' };
            write!(
                f,
                "{:.3} px {sign} {:.3} px x²",
                self.offset_px,
                self.quadratic_px.abs()
            )
        }
    }
}

impl FrameMatches {
    /// The same matches with `correction` added to every disparity: each point `p` of
    /// disparity `d` becomes `p k` with `k = d / (d + δ(p))`, and its covariance
    /// `T Σ Tᵀ` with `T` of `offset_jacobian` (exact for a constant `δ`; the small
    /// change of `δ` across the pixel's own noise is neglected).
    ///
    /// # Errors
    /// [`PoseError::NonFinite`] if the correction makes a disparity non-positive.
    pub fn with_disparity_correction(
        &self,
        correction: DisparityCorrection,
    ) -> Result<Self, PoseError> {
        let c = &self.correspondences;
        let factors = |points: &[Point3<f64>], d: &[f64]| -> Vec<f64> {
            points
                .iter()
                .zip(d)
                .map(|(p, &d)| d / (d + correction.at(p)))
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
                .map(|(&d, p)| d + correction.at(p))
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
    fn quadratic_grows_towards_the_edges_and_constant_matches_the_offset() {
        let c = DisparityCorrection {
            offset_px: 0.5,
            quadratic_px: 2.0,
        };
        assert_eq!(c.at(&Point3::new(0.0, 3.0, 10.0)), 0.5);
        assert!((c.at(&Point3::new(8.0, 0.0, 10.0)) - (0.5 + 2.0 * 0.64)).abs() < 1e-12);
        assert_eq!(c.to_string(), "0.500 px + 2.000 px x²");
        assert_eq!(DisparityCorrection::constant(1.25).to_string(), "1.250 px");
        let negative = DisparityCorrection {
            offset_px: 1.0,
            quadratic_px: -1.5,
        };
        assert_eq!(negative.to_string(), "1.000 px - 1.500 px x²");
    }
}
