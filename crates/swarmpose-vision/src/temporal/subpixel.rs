//! Sub-pixel position of a feature in the next image: where the image patch around a
//! keypoint of image A appears in image B.
//!
//! Feature detectors locate a corner independently in each image, with errors that do
//! not cancel between images: a corner is detected at whole pixels (FAST), and its
//! detected position moves with the corner's apparent size, which changes between frames
//! when the camera moves forward. A motion estimated from such positions has a scale
//! bias. Aligning the patch itself (Lucas-Kanade, translation only) measures the
//! displacement of what A saw.

use crate::features::GrayView;
use crate::image::sample_patch;

/// Largest patch side, pixels.
const MAX_SIDE: usize = 21;

/// Gauss-Newton (inverse compositional Lucas-Kanade, translation) alignment of the
/// `(2 r + 1)²` patch of `a` centred at `at_a` with image `b`, starting at `start_b`:
/// the position in `b` (pixels) that minimises `Σ (B(p + w) − A(at_a + w))²`. `None`
/// when a patch leaves an image, the patch has no texture in one direction, the
/// iterations do not settle, or the result moves more than `max_move_px` from
/// `start_b`. `r` is at most 9.
#[must_use]
pub fn align_patch(
    a: GrayView<'_>,
    at_a: (f32, f32),
    b: GrayView<'_>,
    start_b: (f32, f32),
    r: usize,
    iterations: usize,
    max_move_px: f32,
) -> Option<(f32, f32)> {
    let n = 2 * r + 1;
    if n + 2 > MAX_SIDE {
        return None;
    }
    let ri = r as f32;
    // The template with a one-pixel border, for central-difference gradients.
    let m = n + 2;
    let mut big = [0f32; MAX_SIDE * MAX_SIDE];
    sample_patch(a, at_a.0 - ri - 1.0, at_a.1 - ri - 1.0, m, &mut big)?;
    let mut template = [0f32; MAX_SIDE * MAX_SIDE];
    let mut gx = [0f32; MAX_SIDE * MAX_SIDE];
    let mut gy = [0f32; MAX_SIDE * MAX_SIDE];
    let (mut hxx, mut hxy, mut hyy) = (0f32, 0f32, 0f32);
    for j in 0..n {
        for i in 0..n {
            let c = (j + 1) * m + i + 1;
            let k = j * n + i;
            template[k] = big[c];
            let gxk = 0.5 * (big[c + 1] - big[c - 1]);
            let gyk = 0.5 * (big[c + m] - big[c - m]);
            gx[k] = gxk;
            gy[k] = gyk;
            hxx += gxk * gxk;
            hxy += gxk * gyk;
            hyy += gyk * gyk;
        }
    }
    let det = hxx * hyy - hxy * hxy;
    // Texture in both directions: the smaller eigenvalue of the structure tensor.
    let trace = hxx + hyy;
    let min_eig = 0.5 * (trace - ((hxx - hyy).powi(2) + 4.0 * hxy * hxy).sqrt());
    if det <= 0.0 || min_eig < (n * n) as f32 {
        return None;
    }
    let mut patch = [0f32; MAX_SIDE * MAX_SIDE];
    let (mut px, mut py) = start_b;
    for _ in 0..iterations {
        sample_patch(b, px - ri, py - ri, n, &mut patch)?;
        let (mut ex, mut ey) = (0f32, 0f32);
        for k in 0..n * n {
            let e = patch[k] - template[k];
            ex += gx[k] * e;
            ey += gy[k] * e;
        }
        let dx = (hyy * ex - hxy * ey) / det;
        let dy = (hxx * ey - hxy * ex) / det;
        px -= dx;
        py -= dy;
        if (px - start_b.0).hypot(py - start_b.1) > max_move_px {
            return None;
        }
        if dx.hypot(dy) < 0.01 {
            return Some((px, py));
        }
    }
    None
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A smooth 2D pattern shifted by a known sub-pixel amount is found.
    #[test]
    fn sub_pixel_shift_is_recovered() {
        let (w, h) = (80usize, 60usize);
        let pattern = |x: f32, y: f32| {
            128.0 + 60.0 * (0.31 * x).sin() * (0.23 * y).cos() + 30.0 * (0.17 * (x + y)).sin()
        };
        let (sx, sy) = (1.37f32, -0.62f32);
        let img = |dx: f32, dy: f32| -> Vec<u8> {
            (0..h)
                .flat_map(|y| {
                    (0..w).map(move |x| pattern(x as f32 - dx, y as f32 - dy).round() as u8)
                })
                .collect()
        };
        let (da, db) = (img(0.0, 0.0), img(sx, sy));
        let a = GrayView {
            width: w,
            height: h,
            data: &da,
        };
        let b = GrayView {
            width: w,
            height: h,
            data: &db,
        };
        let found = align_patch(a, (40.0, 30.0), b, (41.0, 30.0), 5, 20, 3.0).expect("aligned");
        assert!((found.0 - 40.0 - sx).abs() < 0.05, "{found:?}");
        assert!((found.1 - 30.0 - sy).abs() < 0.05, "{found:?}");
        // A flat patch has no position.
        let flat = vec![100u8; w * h];
        let f = GrayView {
            width: w,
            height: h,
            data: &flat,
        };
        assert!(align_patch(f, (40.0, 30.0), f, (40.0, 30.0), 5, 20, 3.0).is_none());
    }
}
