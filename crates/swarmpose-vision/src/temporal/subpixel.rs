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
    let mut template = PatchTemplate::empty();
    align_patch_with(&mut template, a, at_a, b, start_b, iterations, max_move_px)
}

/// [`align_patch`] with the patch of `a` sampled into `template`, a buffer the caller
/// keeps between calls (about 6 kB that a returned template would copy each call).
/// Sampling writes every field of the template, so its earlier content never matters: the
/// same answer as [`align_patch`], bit for bit.
#[must_use]
pub fn align_patch_with(
    template: &mut PatchTemplate,
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
    if !template.sample_into(a, at_a) {
        return None;
    }
    template.align(b, start_b, limits)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A `width` x `height` view of `data`.
    fn view(width: usize, height: usize, data: &[u8]) -> GrayView<'_> {
        GrayView {
            width,
            height,
            data,
        }
    }

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
        let a = view(w, h, &da);
        let b = view(w, h, &db);
        let found = align_patch(a, (40.0, 30.0), b, (41.0, 30.0), 20, 3.0).expect("aligned");
        assert!((found.0 - 40.0 - sx).abs() < 0.05, "{found:?}");
        assert!((found.1 - 30.0 - sy).abs() < 0.05, "{found:?}");
        // A flat patch has no position.
        let flat = vec![100u8; w * h];
        let f = view(w, h, &flat);
        assert!(align_patch(f, (40.0, 30.0), f, (40.0, 30.0), 20, 3.0).is_none());
    }

    /// The old [`align_patch`]: a template sampled and returned by value per call.
    fn align_patch_before(
        a: GrayView<'_>,
        at_a: (f32, f32),
        b: GrayView<'_>,
        start_b: (f32, f32),
    ) -> Option<(f32, f32)> {
        let limits = AlignLimits {
            iterations: 20,
            max_move_px: 3.0,
            min_ncc: None,
        };
        PatchTemplate::sample(a, at_a)?.align(b, start_b, limits)
    }

    /// A textured image: smooth waves plus seeded noise, a flat block and a saturated one.
    fn textured(w: usize, h: usize, seed: u64, shift: f32) -> Vec<u8> {
        let mut state = seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) | 1;
        (0..w * h)
            .map(|i| {
                let (x, y) = ((i % w) as f32 - shift, (i / w) as f32);
                state ^= state << 13;
                state ^= state >> 7;
                state ^= state << 17;
                let noise = (state % 9) as f32 - 4.0;
                match (i % w, i / w) {
                    (0..=15, 0..=15) => 90,
                    (60.., 40..) => 255,
                    _ => (128.0 + 60.0 * (0.31 * x).sin() * (0.23 * y).cos() + noise)
                        .clamp(0.0, 255.0) as u8,
                }
            })
            .collect()
    }

    /// One template reused over many alignments, failed ones between them, gives the
    /// bits of a template sampled afresh for each.
    #[test]
    fn a_reused_template_aligns_as_a_fresh_one() {
        let (w, h) = (80usize, 60usize);
        let (da, db) = (textured(w, h, 1, 0.0), textured(w, h, 2, 1.3));
        let a = view(w, h, &da);
        let b = view(w, h, &db);
        let mut template = PatchTemplate::empty();
        let (mut found, mut failed) = (0, 0);
        for k in 0..600 {
            let at = (
                (k * 37 % 97) as f32 * 0.83 - 2.0,
                (k * 53 % 71) as f32 * 0.87 - 2.0,
            );
            let start = (at.0 + 1.1, at.1 - 0.4);
            let before = align_patch_before(a, at, b, start);
            let now = align_patch_with(&mut template, a, at, b, start, 20, 3.0);
            let bits = |p: Option<(f32, f32)>| p.map(|(u, v)| (u.to_bits(), v.to_bits()));
            assert_eq!(bits(now), bits(before), "at {at:?}");
            if now.is_some() {
                found += 1;
            } else {
                failed += 1;
            }
        }
        assert!(
            found > 100 && failed > 100,
            "{found} found, {failed} failed"
        );
    }
}
