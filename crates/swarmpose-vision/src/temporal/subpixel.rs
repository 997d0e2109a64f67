//! Sub-pixel position of a feature in the next image: where the image patch around a
//! keypoint of image A appears in image B.
//!
//! Feature detectors locate a corner independently in each image, with errors that do
//! not cancel between images: a corner is detected at whole pixels (FAST), and its
//! detected position moves with the corner's apparent size, which changes between frames
//! when the camera moves forward. A motion estimated from such positions has a scale
//! bias. Aligning the patch itself (Lucas-Kanade, translation only) measures the
//! displacement of what A saw.

use super::template::{AlignLimits, PatchTemplate};
use crate::features::GrayView;

/// Gauss-Newton (inverse compositional Lucas-Kanade, translation) alignment of the 9x9
/// patch ([`super::template::TEMPLATE_RADIUS`]) of `a` centred at `at_a` with image `b`,
/// starting at `start_b`: the position in `b` (pixels) that minimises
/// `Σ (B(p + w) − A(at_a + w))²`. `None` when a patch leaves an image, the patch has no
/// texture in one direction, the iterations do not settle, or the result moves more than
/// `max_move_px` from `start_b`.
#[must_use]
pub fn align_patch(
    a: GrayView<'_>,
    at_a: (f32, f32),
    b: GrayView<'_>,
    start_b: (f32, f32),
    iterations: usize,
    max_move_px: f32,
) -> Option<(f32, f32)> {
    let limits = AlignLimits {
        iterations,
        max_move_px,
        min_ncc: None,
    };
    PatchTemplate::sample(a, at_a)?.align(b, start_b, limits)
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
        let found = align_patch(a, (40.0, 30.0), b, (41.0, 30.0), 20, 3.0).expect("aligned");
        assert!((found.0 - 40.0 - sx).abs() < 0.05, "{found:?}");
        assert!((found.1 - 30.0 - sy).abs() < 0.05, "{found:?}");
        // A flat patch has no position.
        let flat = vec![100u8; w * h];
        let f = GrayView {
            width: w,
            height: h,
            data: &flat,
        };
        assert!(align_patch(f, (40.0, 30.0), f, (40.0, 30.0), 20, 3.0).is_none());
    }
}
