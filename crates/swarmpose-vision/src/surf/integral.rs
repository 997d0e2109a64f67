//! Integral image (summed-area table) with constant-time box sums.
//!
//! For an image `I`, the integral image is
//!
//! ```text
//! S(x, y) = Σ_{i < x, j < y} I(i, j)
//! ```
//!
//! stored with one leading row and column of zeros (`(w + 1) × (h + 1)` entries), so that
//! the sum over any box `[x0, x1) × [y0, y1)` is four look-ups with no branches:
//!
//! ```text
//! Σ_box I = S(x1, y1) − S(x0, y1) − S(x1, y0) + S(x0, y0).
//! ```
//!
//! Entries are `u32` accumulated with wrapping arithmetic. The box sum is evaluated with
//! wrapping arithmetic too, which is exact modulo 2³², so every box whose true sum is
//! below 2³² (any box of fewer than 2³² / 255 ≈ 16.8 million pixels) is exact even when
//! the running totals of a large image wrap around.

use crate::features::GrayView;

/// Summed-area table of an 8-bit image; see the module documentation.
#[derive(Debug, Clone, Default)]
pub struct IntegralImage {
    width: usize,
    height: usize,
    /// `(width + 1) * (height + 1)` entries; `sums[y * (width + 1) + x] = S(x, y)`.
    sums: Vec<u32>,
    /// The value of a white pixel: 255 for an 8-bit image.
    white: u32,
}

impl IntegralImage {
    /// Builds the integral image of `image` in one pass (`O(w · h)`).
    ///
    /// If `image.data` is shorter than `width * height`, the missing pixels count as 0.
    #[must_use]
    pub fn new(image: GrayView<'_>) -> Self {
        let mut integral = Self::default();
        integral.rebuild(image);
        integral
    }

    /// Rebuilds in place for a new image, reusing the allocation when it is large enough.
    pub fn rebuild(&mut self, image: GrayView<'_>) {
        self.build(image.width, image.height, image.data, 255);
    }

    /// Rebuilds in place for a `width × height` image of 16-bit values, row-major, in
    /// which a white pixel has the value `white` (missing pixels count as 0). Box sums
    /// stay exact while they are below 2³².
    pub fn rebuild_fixed(&mut self, width: usize, height: usize, data: &[u16], white: u32) {
        self.build(width, height, data, white);
    }

    fn build<T: Copy + Into<u32>>(&mut self, w: usize, h: usize, data: &[T], white: u32) {
        let stride = w + 1;
        self.width = w;
        self.height = h;
        self.white = white;
        self.sums.clear();
        self.sums.resize(stride * (h + 1), 0);
        let len = data.len();
        for y in 0..h {
            let row = data
                .get((y * w).min(len)..((y + 1) * w).min(len))
                .unwrap_or(&[]);
            let (above, current) = self.sums.split_at_mut((y + 1) * stride);
            let above = &above[y * stride + 1..];
            let current = &mut current[1..stride];
            // Running sum of the row (sequential), then the row above added (vectorised).
            let mut running = 0u32;
            for (c, &v) in current.iter_mut().zip(row) {
                running = running.wrapping_add(v.into());
                *c = running;
            }
            for c in current.iter_mut().skip(row.len()) {
                *c = running;
            }
            for (c, &a) in current.iter_mut().zip(above) {
                *c = c.wrapping_add(a);
            }
        }
    }

    /// The value of a white pixel in the summed image: 255 for an 8-bit image (at least
    /// 1).
    #[must_use]
    pub fn white(&self) -> u32 {
        self.white.max(1)
    }

    /// Image width, pixels.
    #[must_use]
    pub fn width(&self) -> usize {
        self.width
    }

    /// Image height, pixels.
    #[must_use]
    pub fn height(&self) -> usize {
        self.height
    }

    /// Row stride of [`Self::raw`]: `width + 1`.
    #[must_use]
    pub fn stride(&self) -> usize {
        self.width + 1
    }

    /// The raw table, `S(x, y)` at index `y * stride + x`, for callers that precompute
    /// corner offsets (see [`Self::box_sum_at`]).
    #[must_use]
    pub fn raw(&self) -> &[u32] {
        &self.sums
    }

    /// Sum over `[x0, x1) × [y0, y1)`; the box must lie inside the image
    /// (`x0 ≤ x1 ≤ width`, `y0 ≤ y1 ≤ height`), otherwise this panics on the out-of-range
    /// look-up or returns a meaningless value.
    #[inline]
    #[must_use]
    pub fn box_sum(&self, x0: usize, y0: usize, x1: usize, y1: usize) -> u32 {
        let s = self.stride();
        self.box_sum_at(y0 * s + x0, (y1 - y0) * s, x1 - x0)
    }

    /// Sum over the box whose top-left table index is `top_left` (`y0 * stride + x0`),
    /// `rows_offset = (y1 - y0) * stride` and `cols = x1 - x0`: the four-look-up core of
    /// every box filter.
    #[inline]
    #[must_use]
    pub fn box_sum_at(&self, top_left: usize, rows_offset: usize, cols: usize) -> u32 {
        let s = &self.sums;
        let bottom_left = top_left + rows_offset;
        s[bottom_left + cols]
            .wrapping_sub(s[top_left + cols])
            .wrapping_sub(s[bottom_left])
            .wrapping_add(s[top_left])
    }

    /// Sum over `[x0, x1) × [y0, y1)` intersected with the image (signed corners, any
    /// box, possibly empty): pixels outside the image count as 0.
    #[inline]
    #[must_use]
    pub fn box_sum_clamped(&self, x0: isize, y0: isize, x1: isize, y1: isize) -> u32 {
        let clamp_x = |v: isize| v.clamp(0, self.width as isize) as usize;
        let clamp_y = |v: isize| v.clamp(0, self.height as isize) as usize;
        let (x0, x1) = (clamp_x(x0), clamp_x(x1));
        let (y0, y1) = (clamp_y(y0), clamp_y(y1));
        if x1 <= x0 || y1 <= y0 {
            return 0;
        }
        self.box_sum(x0, y0, x1, y1)
    }
}

/// Haar wavelet responses `(dx, dy)` of side `2 · half` centred on the pixel corner
/// `(cx, cy)` (the point at pixel coordinates `(cx − ½, cy − ½)`):
///
/// ```text
/// dx = Σ right half − Σ left half,   dy = Σ bottom half − Σ top half,
/// ```
///
/// in raw intensity units. Where the wavelet leaves the image, each half is replaced by
/// its mean over the part inside the image times the full half area (0 when a half is
/// entirely outside), so the border does not look like an edge.
#[inline]
#[must_use]
pub(crate) fn haar(integral: &IntegralImage, cx: isize, cy: isize, half: usize) -> (f32, f32) {
    let h = half as isize;
    let (w, ht) = (integral.width as isize, integral.height as isize);
    if cx >= h && cy >= h && cx + h <= w && cy + h <= ht {
        // Nine-corner fast path (the centre corner is not needed).
        let s = &integral.sums;
        let stride = integral.stride();
        let (x0, y0) = ((cx - h) as usize, (cy - h) as usize);
        let i = |u: usize, v: usize| i64::from(s[(y0 + v * half) * stride + x0 + u * half]);
        let (a00, a10, a20) = (i(0, 0), i(1, 0), i(2, 0));
        let (a01, a21) = (i(0, 1), i(2, 1));
        let (a02, a12, a22) = (i(0, 2), i(1, 2), i(2, 2));
        let right = a22 - a12 - a20 + a10;
        let left = a12 - a02 - a10 + a00;
        let bottom = a22 - a02 - a21 + a01;
        let top = a21 - a01 - a20 + a00;
        return ((right - left) as f32, (bottom - top) as f32);
    }
    let half_area = (2 * half * half) as f32;
    let mean = |x0: isize, y0: isize, x1: isize, y1: isize| -> Option<f32> {
        let cx0 = x0.clamp(0, w);
        let cx1 = x1.clamp(0, w);
        let cy0 = y0.clamp(0, ht);
        let cy1 = y1.clamp(0, ht);
        let area = (cx1 - cx0) * (cy1 - cy0);
        (area > 0).then(|| integral.box_sum_clamped(x0, y0, x1, y1) as f32 / area as f32)
    };
    let diff = |a: Option<f32>, b: Option<f32>| match (a, b) {
        (Some(a), Some(b)) => (a - b) * half_area,
        _ => 0.0,
    };
    let dx = diff(
        mean(cx, cy - h, cx + h, cy + h),
        mean(cx - h, cy - h, cx, cy + h),
    );
    let dy = diff(
        mean(cx - h, cy, cx + h, cy + h),
        mean(cx - h, cy - h, cx + h, cy),
    );
    (dx, dy)
}

/// The pixel corner nearest to `v` (pixel coordinates): corner `k` sits at `k − ½`.
#[inline]
#[must_use]
pub(crate) fn nearest_corner(v: f32) -> isize {
    (v + 1.0).floor() as isize
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Small deterministic pseudo-random image.
    pub(crate) fn noise_image(w: usize, h: usize, seed: u64) -> Vec<u8> {
        let mut state = seed
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        (0..w * h)
            .map(|_| {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                (state >> 56) as u8
            })
            .collect()
    }

    #[test]
    fn box_sums_match_brute_force() {
        let (w, h) = (37, 23);
        let data = noise_image(w, h, 7);
        let ii = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &data,
        });
        assert_eq!(ii.raw().len(), (w + 1) * (h + 1));
        let brute = |x0: usize, y0: usize, x1: usize, y1: usize| -> u32 {
            let mut s = 0u32;
            for y in y0..y1 {
                for x in x0..x1 {
                    s += u32::from(data[y * w + x]);
                }
            }
            s
        };
        for (x0, y0, x1, y1) in [
            (0, 0, w, h),
            (0, 0, 1, 1),
            (3, 4, 3, 9),
            (5, 2, 17, 11),
            (w - 1, h - 1, w, h),
            (10, 0, 30, 23),
        ] {
            assert_eq!(ii.box_sum(x0, y0, x1, y1), brute(x0, y0, x1, y1));
        }
        let mut k = 0;
        for y0 in (0..h).step_by(3) {
            for x0 in (0..w).step_by(5) {
                let x1 = (x0 + 1 + k % 13).min(w);
                let y1 = (y0 + 1 + k % 7).min(h);
                k += 1;
                assert_eq!(ii.box_sum(x0, y0, x1, y1), brute(x0, y0, x1, y1));
            }
        }
        // Clamped sums count the outside as zero.
        assert_eq!(ii.box_sum_clamped(-5, -5, 4, 3), brute(0, 0, 4, 3));
        assert_eq!(ii.box_sum_clamped(30, 20, 99, 99), brute(30, 20, w, h));
        assert_eq!(ii.box_sum_clamped(-9, -9, -1, 5), 0);
        assert_eq!(ii.box_sum_clamped(8, 8, 8, 12), 0);
    }

    #[test]
    fn wrapping_totals_still_give_exact_boxes() {
        // 4200 × 4200 of 255 overflows u32 in the total (4.5e9), boxes stay exact.
        let (w, h) = (4200, 4200);
        let data = vec![255u8; w * h];
        let ii = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &data,
        });
        assert_eq!(ii.box_sum(4100, 4100, 4200, 4200), 255 * 100 * 100);
        assert_eq!(ii.box_sum(0, 0, 4000, 4000), 255 * 4000 * 4000);
    }

    #[test]
    fn short_data_counts_as_zero() {
        let data = [1u8, 2, 3];
        let ii = IntegralImage::new(GrayView {
            width: 2,
            height: 2,
            data: &data,
        });
        assert_eq!(ii.box_sum(0, 0, 2, 2), 6);
    }

    #[test]
    fn haar_matches_box_sums_inside_and_ignores_the_outside() {
        let (w, h) = (30, 20);
        let data = noise_image(w, h, 3);
        let ii = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &data,
        });
        let (dx, dy) = haar(&ii, 10, 9, 3);
        let b = |x0, y0, x1, y1| ii.box_sum(x0, y0, x1, y1) as f32;
        assert_eq!(dx, b(10, 6, 13, 12) - b(7, 6, 10, 12));
        assert_eq!(dy, b(7, 9, 13, 12) - b(7, 6, 13, 9));
        // Constant image: no response anywhere, even across the border.
        let flat = vec![200u8; w * h];
        let ii = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &flat,
        });
        for (cx, cy) in [(0, 0), (1, 5), (29, 19), (30, 20), (-2, 4), (15, 10)] {
            assert_eq!(haar(&ii, cx, cy, 4), (0.0, 0.0));
        }
        assert_eq!(nearest_corner(3.0), 4);
        assert_eq!(nearest_corner(2.6), 3);
        assert_eq!(nearest_corner(2.4), 3);
        assert_eq!(nearest_corner(3.2), 4);
        assert_eq!(nearest_corner(-0.2), 0);
    }
}
