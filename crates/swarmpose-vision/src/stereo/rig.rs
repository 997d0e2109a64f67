//! The rectified stereo camera model and triangulation.

use nalgebra::Point3;

/// A rectified stereo pair: both cameras share the intrinsics below, have parallel
/// optical axes, and the right camera sits `baseline_m` along `+x` of the left camera.
/// A left pixel `(u, v)` matches a right pixel `(u - d, v)` with disparity `d > 0`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RectifiedStereo {
    /// Focal length along x, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point column, pixels.
    pub cx: f64,
    /// Principal point row, pixels.
    pub cy: f64,
    /// Distance between the camera centres, metres (> 0).
    pub baseline_m: f64,
}

impl RectifiedStereo {
    /// The point, metres in the LEFT camera frame (x right, y down, z forward), seen at
    /// left pixel `(u, v)` with disparity `d` pixels: `Z = fx b / d`, `X = (u - cx) Z /
    /// fx`, `Y = (v - cy) Z / fy`. `None` for a disparity that is not positive.
    #[must_use]
    pub fn triangulate(&self, u: f64, v: f64, d: f64) -> Option<Point3<f64>> {
        if d.is_nan() || d <= 0.0 {
            return None;
        }
        let z = self.fx * self.baseline_m / d;
        Some(Point3::new(
            (u - self.cx) * z / self.fx,
            (v - self.cy) * z / self.fy,
            z,
        ))
    }

    /// Projection of a left-camera point (metres) into the left image: `(u, v)` pixels.
    #[must_use]
    pub fn project_left(&self, p: &Point3<f64>) -> (f64, f64) {
        (self.fx * p.x / p.z + self.cx, self.fy * p.y / p.z + self.cy)
    }

    /// Depth uncertainty, metres, of a point at depth `z_m` for a disparity error of
    /// `sigma_d_px` pixels: `z² σ_d / (fx b)`.
    #[must_use]
    pub fn depth_sigma(&self, z_m: f64, sigma_d_px: f64) -> f64 {
        z_m * z_m * sigma_d_px / (self.fx * self.baseline_m)
    }

    /// Isotropic noise level of a triangulated point at depth `z_m`, metres: the root
    /// sum of squares of the depth deviation ([`RectifiedStereo::depth_sigma`]) and of
    /// the two lateral deviations `z σ_p / f` for a keypoint deviation `sigma_p_px`.
    #[must_use]
    pub fn point_sigma(&self, z_m: f64, sigma_d_px: f64, sigma_p_px: f64) -> f64 {
        let dz = self.depth_sigma(z_m, sigma_d_px);
        let lateral = z_m * sigma_p_px / self.fx;
        (dz * dz + 2.0 * lateral * lateral).sqrt()
    }

    /// Covariance, m², of the point triangulated at left pixel `(u, v)` with disparity
    /// `d`, for independent errors of `sigma_p_px` on `u` and `v` and `sigma_d_px` on
    /// `d` (first-order propagation): elongated along the viewing ray.
    #[must_use]
    pub fn point_covariance(
        &self,
        u: f64,
        v: f64,
        d: f64,
        sigma_p_px: f64,
        sigma_d_px: f64,
    ) -> nalgebra::Matrix3<f64> {
        let b = self.baseline_m;
        let x = (u - self.cx) * b / d;
        let y = (v - self.cy) * b * self.fx / (self.fy * d);
        let z = self.fx * b / d;
        let j = nalgebra::Matrix3::new(
            b / d,
            0.0,
            -x / d,
            0.0,
            b * self.fx / (self.fy * d),
            -y / d,
            0.0,
            0.0,
            -z / d,
        );
        let s = nalgebra::Matrix3::from_diagonal(&nalgebra::Vector3::new(
            sigma_p_px * sigma_p_px,
            sigma_p_px * sigma_p_px,
            sigma_d_px * sigma_d_px,
        ));
        j * s * j.transpose()
    }
}
