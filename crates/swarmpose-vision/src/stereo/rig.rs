//! The rectified stereo camera model and triangulation.

use nalgebra::Point3;

/// The stereo baselines accepted, metres: from 5 mm (the smallest stereo modules) to
/// 10 m (wide rigs on vehicles). A value outside is a malformed or mis-scaled number (a
/// baseline in millimetres, a missing minus sign), refused rather than giving points a
/// thousand times too near or too far.
pub const BASELINE_RANGE_M: (f64, f64) = (0.005, 10.0);

/// The focal lengths accepted, as multiples of the image's larger side: 0.05 to 50, a
/// field of view across that side from about 169 down to 1.1 degrees. Outside, the
/// number is not a focal length for these images (a focal length in millimetres, one
/// of an image of another size).
pub const FOCAL_RANGE: (f64, f64) = (0.05, 50.0);

/// The largest ratio of `fx` to `fy` (or `fy` to `fx`) accepted: pixels are square to
/// within this factor on every camera a rectified pair is made from.
pub const MAX_PIXEL_ASPECT: f64 = 2.0;

/// How far outside the image the principal point may lie, as a fraction of its width
/// (`cx`) or height (`cy`): rectification and cropping move it, but not off the image.
pub const PRINCIPAL_POINT_MARGIN: f64 = 0.25;

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
    /// Why these numbers are not a plausible rectified stereo camera for images of
    /// `width` x `height` pixels, or `None`: focal lengths within [`FOCAL_RANGE`] of the
    /// larger side, `fx / fy` within [`MAX_PIXEL_ASPECT`], the principal point within
    /// [`PRINCIPAL_POINT_MARGIN`] of the image. The one check of every loader and of the
    /// engine. The baseline is not checked here: the engine works in any unit of length
    /// (a rig given in millimetres gives the same motions in millimetres), so only the
    /// loaders, whose files are in metres, hold it to [`BASELINE_RANGE_M`].
    #[must_use]
    pub fn implausibility(&self, width: usize, height: usize) -> Option<String> {
        let size = format!("{width}x{height}");
        let (w, h) = (width as f64, height as f64);
        let (lo, hi) = FOCAL_RANGE;
        let side = w.max(h);
        for (name, f) in [("fx", self.fx), ("fy", self.fy)] {
            if !(lo * side..=hi * side).contains(&f) {
                return Some(format!(
                    "{name} = {f} px is not a focal length for {size} images ({lo} to {hi} \
                     times the larger side accepted: {:.0} to {:.0} px)",
                    lo * side,
                    hi * side
                ));
            }
        }
        let aspect = self.fx / self.fy;
        if !(1.0 / MAX_PIXEL_ASPECT..=MAX_PIXEL_ASPECT).contains(&aspect) {
            return Some(format!(
                "fx / fy = {aspect:.3} (fx = {}, fy = {}): pixels are square to within a \
                 factor of {MAX_PIXEL_ASPECT}",
                self.fx, self.fy
            ));
        }
        let m = PRINCIPAL_POINT_MARGIN;
        for (name, c, extent) in [("cx", self.cx, w), ("cy", self.cy, h)] {
            if !(-m * extent..=(1.0 + m) * extent).contains(&c) {
                return Some(format!(
                    "{name} = {c} px is outside the {size} image ({:.0} to {:.0} px accepted: \
                     the image and a quarter of its size around it)",
                    -m * extent,
                    (1.0 + m) * extent
                ));
            }
        }
        None
    }

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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn implausible_cameras_are_named() {
        let kitti = RectifiedStereo {
            fx: 718.856,
            fy: 718.856,
            cx: 607.19,
            cy: 185.22,
            baseline_m: 0.537,
        };
        assert_eq!(kitti.implausibility(1241, 376), None);
        let cases = [
            (
                RectifiedStereo { fx: 7.0, ..kitti },
                "fx = 7 px is not a focal length for 1241x376 images",
            ),
            (RectifiedStereo { fy: 1e6, ..kitti }, "fy = 1000000 px"),
            (RectifiedStereo { fy: 300.0, ..kitti }, "fx / fy = 2.396"),
            (
                RectifiedStereo {
                    cx: 6071.9,
                    ..kitti
                },
                "cx = 6071.9 px is outside the 1241x376 image",
            ),
            (
                RectifiedStereo {
                    cy: -100.0,
                    ..kitti
                },
                "cy = -100 px",
            ),
            (
                RectifiedStereo {
                    cy: f64::NAN,
                    ..kitti
                },
                "cy = NaN px",
            ),
        ];
        for (rig, message) in cases {
            let m = rig.implausibility(1241, 376).unwrap_or_default();
            assert!(m.starts_with(message), "{m}");
        }
        // The same camera for images of a tenth of the size is not plausible; a rig in
        // millimetres is (the engine is free of units).
        assert!(kitti.implausibility(124, 37).is_some());
        let millimetres = RectifiedStereo {
            baseline_m: 537.0,
            ..kitti
        };
        assert_eq!(millimetres.implausibility(1241, 376), None);
    }
}
