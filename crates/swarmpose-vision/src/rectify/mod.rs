//! Undistortion and stereo rectification of raw pinhole cameras with radial-tangential
//! distortion (EuRoC style), and bilinear remapping.
//!
//! Rectification rotates both cameras about their centres so that their optical axes
//! are parallel and their x axes lie along the baseline (Bouguet/Fusiello style: the new
//! x axis is the baseline direction, the new z axis the mean of the two optical axes, so
//! the relative rotation is split evenly), and gives both a common pinhole matrix. A
//! scene point then appears on the same row in both rectified images.

use nalgebra::{Matrix3, Vector3};

use crate::features::GrayView;
use crate::image::{GrayImage, sample_bilinear};
use crate::stereo::RectifiedStereo;

/// A pinhole camera with radial-tangential (Brown-Conrady `k1, k2, p1, p2`) distortion.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RadTanCamera {
    /// Focal lengths and principal point, pixels.
    pub fx: f64,
    /// Focal length along y, pixels.
    pub fy: f64,
    /// Principal point column, pixels.
    pub cx: f64,
    /// Principal point row, pixels.
    pub cy: f64,
    /// Radial coefficient of r².
    pub k1: f64,
    /// Radial coefficient of r⁴.
    pub k2: f64,
    /// Tangential coefficient p1.
    pub p1: f64,
    /// Tangential coefficient p2.
    pub p2: f64,
    /// Image width, pixels.
    pub width: usize,
    /// Image height, pixels.
    pub height: usize,
}

impl RadTanCamera {
    /// Pixel `(u, v)` of the undistorted normalised coordinates `(x, y) = (X/Z, Y/Z)`.
    #[must_use]
    pub fn distort_project(&self, x: f64, y: f64) -> (f64, f64) {
        let r2 = x * x + y * y;
        let radial = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
        let xd = x * radial + 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x);
        let yd = y * radial + self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y;
        (self.fx * xd + self.cx, self.fy * yd + self.cy)
    }

    /// Undistorted normalised coordinates of pixel `(u, v)` (fixed-point iteration, 20
    /// steps; accurate to well under 0.01 pixel for EuRoC-like lenses).
    #[must_use]
    pub fn undistort_pixel(&self, u: f64, v: f64) -> (f64, f64) {
        let (xd, yd) = ((u - self.cx) / self.fx, (v - self.cy) / self.fy);
        let (mut x, mut y) = (xd, yd);
        for _ in 0..20 {
            let r2 = x * x + y * y;
            let radial = 1.0 + self.k1 * r2 + self.k2 * r2 * r2;
            let dx = 2.0 * self.p1 * x * y + self.p2 * (r2 + 2.0 * x * x);
            let dy = self.p1 * (r2 + 2.0 * y * y) + 2.0 * self.p2 * x * y;
            x = (xd - dx) / radial;
            y = (yd - dy) / radial;
        }
        (x, y)
    }
}

/// Why rectification failed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum RectifyError {
    /// The cameras share a centre (no baseline), or the baseline is along the optical
    /// axis.
    #[error("cannot rectify: {0}")]
    Degenerate(String),
}

/// The result of [`stereo_rectify`].
#[derive(Debug, Clone, PartialEq)]
pub struct StereoRectification {
    /// Rotation from the raw left camera frame to the rectified left frame.
    pub rect_from_left: Matrix3<f64>,
    /// Rotation from the raw right camera frame to the rectified right frame.
    pub rect_from_right: Matrix3<f64>,
    /// The rectified pair (common intrinsics, baseline metres).
    pub rig: RectifiedStereo,
    /// Rectified image size, pixels (that of the left camera).
    pub width: usize,
    /// Rectified image height, pixels.
    pub height: usize,
}

/// Rectifying rotations and common intrinsics for a stereo pair whose extrinsics are
/// `X_right = r_right_left X_left + t_right_left` (metres). The right camera must lie
/// roughly along `+x` of the left one.
///
/// # Errors
/// [`RectifyError::Degenerate`] for a zero or forward-pointing baseline.
pub fn stereo_rectify(
    left: &RadTanCamera,
    right: &RadTanCamera,
    r_right_left: &Matrix3<f64>,
    t_right_left: &Vector3<f64>,
) -> Result<StereoRectification, RectifyError> {
    // Right camera centre in the left frame.
    let c_right = -(r_right_left.transpose() * t_right_left);
    let baseline = c_right.norm();
    if baseline.is_nan() || baseline <= 1e-9 || c_right.x.abs() < 0.5 * baseline {
        return Err(RectifyError::Degenerate(format!(
            "the right camera centre ({:.4}, {:.4}, {:.4}) m is not beside the left one",
            c_right.x, c_right.y, c_right.z
        )));
    }
    let ex = c_right / baseline * c_right.x.signum();
    let z_left = Vector3::z();
    let z_right = r_right_left.transpose() * Vector3::z();
    let z_mean = (z_left + z_right).normalize();
    let ey = z_mean.cross(&ex).normalize();
    let ez = ex.cross(&ey);
    let rect_from_left = Matrix3::from_rows(&[ex.transpose(), ey.transpose(), ez.transpose()]);
    let rect_from_right = rect_from_left * r_right_left.transpose();
    let f = left.fx.min(left.fy).min(right.fx).min(right.fy);
    // Keep the raw principal rays near their raw principal points.
    let mut c = (0.0, 0.0);
    for (cam, r) in [(left, &rect_from_left), (right, &rect_from_right)] {
        let ray = r * Vector3::z();
        c.0 += 0.5 * (cam.cx - f * ray.x / ray.z);
        c.1 += 0.5 * (cam.cy - f * ray.y / ray.z);
    }
    Ok(StereoRectification {
        rect_from_left,
        rect_from_right,
        rig: RectifiedStereo {
            fx: f,
            fy: f,
            cx: c.0,
            cy: c.1,
            baseline_m: baseline,
        },
        width: left.width,
        height: left.height,
    })
}

/// For each rectified pixel, where to sample the raw image: `map[y * width + x]` is a
/// raw pixel position `(u, v)`.
#[derive(Debug, Clone, PartialEq)]
pub struct RemapTable {
    /// Output width, pixels.
    pub width: usize,
    /// Output height, pixels.
    pub height: usize,
    /// Raw pixel positions, row-major.
    pub map: Vec<(f32, f32)>,
}

/// The remap table of one camera: rectified pixel → ray in the rectified frame → raw
/// camera frame (`rect_from_cam` transposed) → distortion → raw pixel.
#[must_use]
pub fn rectify_map(
    cam: &RadTanCamera,
    rect_from_cam: &Matrix3<f64>,
    rig: &RectifiedStereo,
    width: usize,
    height: usize,
) -> RemapTable {
    let cam_from_rect = rect_from_cam.transpose();
    let mut map = Vec::with_capacity(width * height);
    for y in 0..height {
        for x in 0..width {
            let ray = Vector3::new(
                (x as f64 - rig.cx) / rig.fx,
                (y as f64 - rig.cy) / rig.fy,
                1.0,
            );
            let p = cam_from_rect * ray;
            let (u, v) = if p.z > 1e-9 {
                cam.distort_project(p.x / p.z, p.y / p.z)
            } else {
                (-1.0, -1.0)
            };
            map.push((u as f32, v as f32));
        }
    }
    RemapTable { width, height, map }
}

/// Resamples `img` through `table` with bilinear interpolation; pixels that map outside
/// the raw image are black.
#[must_use]
pub fn remap(img: GrayView<'_>, table: &RemapTable) -> GrayImage {
    let data = table
        .map
        .iter()
        .map(|&(u, v)| sample_bilinear(img, u, v).map_or(0, |s| (s + 0.5).min(255.0) as u8))
        .collect();
    GrayImage {
        width: table.width,
        height: table.height,
        data,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Point3, Rotation3};

    fn cam(cx: f64) -> RadTanCamera {
        RadTanCamera {
            fx: 458.0,
            fy: 457.0,
            cx,
            cy: 248.0,
            k1: -0.28,
            k2: 0.07,
            p1: 2e-4,
            p2: 2e-5,
            width: 752,
            height: 480,
        }
    }

    #[test]
    fn undistort_inverts_distort() {
        let c = cam(367.0);
        let (u, v) = c.distort_project(0.3, -0.2);
        let (x, y) = c.undistort_pixel(u, v);
        assert!((x - 0.3).abs() < 1e-6 && (y + 0.2).abs() < 1e-6, "{x} {y}");
    }

    #[test]
    fn rectified_points_share_a_row() {
        let (l, r) = (cam(367.0), cam(380.0));
        let rot = Rotation3::from_euler_angles(0.01, -0.02, 0.005);
        let t = -(rot * Vector3::new(0.11, 0.001, 0.002));
        let rect = stereo_rectify(&l, &r, rot.matrix(), &t).expect("rectify");
        assert!((rect.rig.baseline_m - (0.11f64.powi(2) + 1e-6 + 4e-6).sqrt()).abs() < 1e-9);
        for p in [Point3::new(0.5, -0.3, 3.0), Point3::new(-1.0, 0.8, 6.0)] {
            let pl = rect.rect_from_left * p.coords;
            let pr = rect.rect_from_right * (rot * p.coords + t);
            let vl = rect.rig.fy * pl.y / pl.z + rect.rig.cy;
            let vr = rect.rig.fy * pr.y / pr.z + rect.rig.cy;
            assert!((vl - vr).abs() < 1e-9, "{vl} {vr}");
            let d = rect.rig.fx * (pl.x / pl.z - pr.x / pr.z);
            assert!((rect.rig.fx * rect.rig.baseline_m / d - pl.z).abs() < 1e-9);
        }
    }
}
