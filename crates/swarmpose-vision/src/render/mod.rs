//! A small ray-casting renderer of textured planes for tests without data: pinhole
//! cameras (any pose) looking at planes that carry a seeded random texture, so the
//! depth of every pixel is known exactly.

use nalgebra::{Isometry3, Point3, Vector3};

use crate::image::GrayImage;
use crate::stereo::RectifiedStereo;

/// A textured plane: the points `origin + s u + t v` (metres), with `u`, `v` orthonormal.
#[derive(Debug, Clone, PartialEq)]
pub struct TexturedPlane {
    /// A point of the plane, metres (world frame).
    pub origin: Point3<f64>,
    /// First in-plane axis (unit).
    pub u: Vector3<f64>,
    /// Second in-plane axis (unit, orthogonal to `u`).
    pub v: Vector3<f64>,
    /// Size of one texture cell, metres.
    pub cell_m: f64,
    /// Seed of the texture values.
    pub seed: u64,
}

impl TexturedPlane {
    /// A plane facing the camera at depth `z_m` (normal along `z`), texture cells of
    /// `cell_m` metres.
    #[must_use]
    pub fn fronto_parallel(z_m: f64, cell_m: f64, seed: u64) -> Self {
        Self {
            origin: Point3::new(0.0, 0.0, z_m),
            u: Vector3::x(),
            v: Vector3::y(),
            cell_m,
            seed,
        }
    }

    fn normal(&self) -> Vector3<f64> {
        self.u.cross(&self.v)
    }

    /// Texture value of cell `(i, j)`, 0..255: a hash of the seed and the cell.
    fn cell(&self, i: i64, j: i64) -> f64 {
        let mut z = self
            .seed
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .wrapping_add((i as u64).wrapping_mul(0xbf58_476d_1ce4_e5b9))
            .wrapping_add((j as u64).wrapping_mul(0x94d0_49bb_1331_11eb));
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^= z >> 31;
        20.0 + (z % 216) as f64
    }

    /// Intensity at plane coordinates `(s, t)` metres: random values at the cell
    /// corners, bilinearly interpolated (value noise), so edges fall between pixels
    /// smoothly instead of in steps of the supersampling.
    fn texture(&self, s: f64, t: f64) -> f64 {
        let (a, b) = (s / self.cell_m, t / self.cell_m);
        let (i, j) = (a.floor(), b.floor());
        let (fa, fb) = (a - i, b - j);
        let (i, j) = (i as i64, j as i64);
        let top = self.cell(i, j) * (1.0 - fa) + self.cell(i + 1, j) * fa;
        let bot = self.cell(i, j + 1) * (1.0 - fa) + self.cell(i + 1, j + 1) * fa;
        top * (1.0 - fb) + bot * fb
    }
}

/// The ray `origin + λ dir` (world frame) hits `plane` at `λ`, if in front.
fn hit(plane: &TexturedPlane, origin: &Point3<f64>, dir: &Vector3<f64>) -> Option<f64> {
    let n = plane.normal();
    let denom = n.dot(dir);
    if denom.abs() < 1e-12 {
        return None;
    }
    let lambda = n.dot(&(plane.origin - origin)) / denom;
    (lambda > 0.0).then_some(lambda)
}

/// Renders what a pinhole camera at `world_from_camera` sees of `planes` (nearest
/// plane per ray; black where none), with `samples`² supersampling per pixel.
/// Intrinsics are those of `camera` (pixels).
#[must_use]
pub fn render(
    camera: &RectifiedStereo,
    world_from_camera: &Isometry3<f64>,
    width: usize,
    height: usize,
    planes: &[TexturedPlane],
    samples: usize,
) -> GrayImage {
    let samples = samples.max(1);
    let origin = world_from_camera * Point3::origin();
    let mut img = GrayImage::new(width, height);
    for y in 0..height {
        for x in 0..width {
            let mut acc = 0.0;
            for sy in 0..samples {
                for sx in 0..samples {
                    let px = x as f64 - 0.5 + (sx as f64 + 0.5) / samples as f64;
                    let py = y as f64 - 0.5 + (sy as f64 + 0.5) / samples as f64;
                    let d_cam = Vector3::new(
                        (px - camera.cx) / camera.fx,
                        (py - camera.cy) / camera.fy,
                        1.0,
                    );
                    let dir = world_from_camera.rotation * d_cam;
                    let best = planes
                        .iter()
                        .filter_map(|p| hit(p, &origin, &dir).map(|l| (l, p)))
                        .min_by(|a, b| a.0.total_cmp(&b.0));
                    if let Some((l, p)) = best {
                        let q = origin + dir * l - p.origin;
                        acc += p.texture(q.dot(&p.u), q.dot(&p.v));
                    }
                }
            }
            img.data[y * width + x] = (acc / (samples * samples) as f64).round() as u8;
        }
    }
    img
}

/// Depth (camera `z`, metres) of the nearest plane seen at pixel `(u, v)` by a camera at
/// `world_from_camera`, or `None`.
#[must_use]
pub fn depth_at(
    camera: &RectifiedStereo,
    world_from_camera: &Isometry3<f64>,
    planes: &[TexturedPlane],
    u: f64,
    v: f64,
) -> Option<f64> {
    let origin = world_from_camera * Point3::origin();
    let d_cam = Vector3::new(
        (u - camera.cx) / camera.fx,
        (v - camera.cy) / camera.fy,
        1.0,
    );
    let dir = world_from_camera.rotation * d_cam;
    planes
        .iter()
        .filter_map(|p| hit(p, &origin, &dir))
        .min_by(f64::total_cmp)
}
