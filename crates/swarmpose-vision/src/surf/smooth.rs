//! Gaussian smoothing of the input image before the box filters of an octave.
//!
//! The detector smooths the image of octave `o ≥ 1` with a Gaussian of standard
//! deviation `σ_o` (see [`super::SurfConfig::smoothing`]) and builds an integral image of
//! the result. The Gaussian is approximated by three successive box blurs of nearly equal
//! widths (the "extended box" approximation, Wells 1986), each a four-look-up mean on an
//! integral image, so that the cost does not depend on `σ`. Values are kept in fixed
//! point with [`FIXED_ONE`] steps per grey level, so the rounding does not flatten weak
//! structures. Near the border each box is cut to the image and its mean taken over the
//! part inside.

use super::integral::IntegralImage;

/// Fixed-point steps per grey level in the smoothed images: a white pixel is
/// `255 · FIXED_ONE`, and a box sum of the largest filter (195 × 195) stays far below 2³².
pub(crate) const FIXED_ONE: u16 = 16;

/// The integral image of the image summed in `plain` smoothed by a Gaussian of standard
/// deviation `sigma` pixels, written to `out` (reusing its allocation); `fixed` is
/// scratch space. Returns `false`, leaving `out` untouched, when `sigma` is too small to
/// change the image (every box of width 1).
pub(crate) fn smoothed_integral(
    plain: &IntegralImage,
    sigma: f32,
    fixed: &mut Vec<u16>,
    out: &mut IntegralImage,
) -> bool {
    let (w, h) = (plain.width(), plain.height());
    if sigma <= 0.0 || w == 0 || h == 0 {
        return false;
    }
    let white = 255 * u32::from(FIXED_ONE);
    let mut smoothed = false;
    for width in box_widths(sigma) {
        if width > 1 {
            box_mean(if smoothed { out } else { plain }, width / 2, white, fixed);
            out.rebuild_fixed(w, h, fixed, white);
            smoothed = true;
        }
    }
    smoothed
}

/// Odd widths of three boxes whose successive application has variance closest to
/// `σ²`: `m` boxes of width `wl` and `3 − m` of width `wl + 2` (a box of width `w` has
/// variance `(w² − 1) / 12`).
pub(crate) fn box_widths(sigma: f32) -> [usize; 3] {
    let var12 = 12.0 * sigma * sigma;
    let ideal = (var12 / 3.0 + 1.0).sqrt();
    let mut wl = ideal.floor() as usize;
    if wl.is_multiple_of(2) {
        wl = wl.saturating_sub(1);
    }
    let wl = wl.max(1);
    let wlf = wl as f32;
    let m = ((var12 - 3.0 * wlf * wlf - 12.0 * wlf - 9.0) / (-4.0 * wlf - 4.0)).round();
    let m = m.clamp(0.0, 3.0) as usize;
    [0, 1, 2].map(|i| if i < m { wl } else { wl + 2 })
}

/// The mean of the image summed in `integral` over the `(2r + 1)²` box around each
/// pixel (cut to the image), in fixed point where white is `white`, into `out`.
fn box_mean(integral: &IntegralImage, r: usize, white: u32, out: &mut Vec<u16>) {
    let (w, h) = (integral.width(), integral.height());
    let to_fixed = white as f32 / integral.white() as f32;
    out.clear();
    out.resize(w * h, 0);
    let side = 2 * r + 1;
    let stride = integral.stride();
    let sums = integral.raw();
    for (y, row) in out.chunks_exact_mut(w).enumerate() {
        if w < side {
            for (x, o) in row.iter_mut().enumerate() {
                *o = clamped_mean(integral, x, y, r, to_fixed);
            }
            continue;
        }
        // Columns r..w-r: the box is whole across, cut to the image vertically; four
        // shifted slices of the table.
        let (y0, y1) = (y.saturating_sub(r), (y + r + 1).min(h));
        // mean · to_fixed = (sum · m + ½ 2^28) >> 28 with m = 2^28 · to_fixed / area, in
        // integers (sum · m < 2^45), which vectorises where the float conversion did not.
        let area = (side * (y1 - y0)) as f64;
        let m = (f64::from(to_fixed) * f64::from(1u32 << 28) / area).round() as u64;
        let n = w - 2 * r;
        let (top, bottom) = (y0 * stride, y1 * stride);
        let a = &sums[top..top + n];
        let b = &sums[top + side..top + side + n];
        let c = &sums[bottom..bottom + n];
        let d = &sums[bottom + side..bottom + side + n];
        for ((((o, a), b), c), d) in row[r..w - r].iter_mut().zip(a).zip(b).zip(c).zip(d) {
            let sum = d.wrapping_sub(*b).wrapping_sub(*c).wrapping_add(*a);
            *o = ((u64::from(sum) * m + (1 << 27)) >> 28) as u16;
        }
        for x in (0..r).chain(w - r..w) {
            row[x] = clamped_mean(integral, x, y, r, to_fixed);
        }
    }
}

/// Mean over the box of radius `r` around `(x, y)` cut to the image, times `to_fixed`.
fn clamped_mean(integral: &IntegralImage, x: usize, y: usize, r: usize, to_fixed: f32) -> u16 {
    let (w, h) = (integral.width(), integral.height());
    let (x0, y0) = (x.saturating_sub(r), y.saturating_sub(r));
    let (x1, y1) = ((x + r + 1).min(w), (y + r + 1).min(h));
    let area = ((x1 - x0) * (y1 - y0)).max(1) as f32;
    (integral.box_sum(x0, y0, x1, y1) as f32 / area * to_fixed + 0.5) as u16
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::GrayView;

    fn variance_of_boxes(widths: [usize; 3]) -> f32 {
        widths
            .iter()
            .map(|&w| ((w * w - 1) as f32) / 12.0)
            .sum::<f32>()
    }

    #[test]
    fn box_widths_match_the_variance() {
        for sigma in [1.5f32, 2.0, 3.0, 4.0, 8.0, 9.6] {
            let widths = box_widths(sigma);
            assert!(widths.iter().all(|w| w % 2 == 1), "{widths:?}");
            let s = variance_of_boxes(widths).sqrt();
            assert!(
                (s - sigma).abs() < 0.25,
                "sigma {sigma}: {widths:?} gives {s}"
            );
        }
    }

    /// Smoothing an impulse spreads it with the requested standard deviation and keeps
    /// the total; a constant image stays constant.
    #[test]
    fn smoothing_preserves_mass_and_has_the_requested_spread() {
        let n = 81;
        for sigma in [1.0f32, 2.0, 4.0] {
            let mut img = vec![0u8; n * n];
            img[40 * n + 40] = 255;
            let view = GrayView {
                width: n,
                height: n,
                data: &img,
            };
            let mut ii = IntegralImage::default();
            assert!(smoothed_integral(
                &IntegralImage::new(view),
                sigma,
                &mut Vec::new(),
                &mut ii
            ));
            let white = f64::from(ii.white());
            let total = f64::from(ii.box_sum(0, 0, n, n)) / white;
            assert!((total - 1.0).abs() < 0.02, "sigma {sigma}: mass {total}");
            // Variance along x from the column sums.
            let mut var = 0.0;
            for x in 0..n {
                let col = f64::from(ii.box_sum(x, 0, x + 1, n)) / white;
                var += col * (x as f64 - 40.0).powi(2);
            }
            let s = (var / total).sqrt() as f32;
            assert!((s - sigma).abs() < 0.2, "sigma {sigma}: spread {s}");
        }
        let flat = vec![123u8; 30 * 20];
        let plain = IntegralImage::new(GrayView {
            width: 30,
            height: 20,
            data: &flat,
        });
        let mut ii = IntegralImage::default();
        assert!(smoothed_integral(&plain, 3.0, &mut Vec::new(), &mut ii));
        assert_eq!(ii.box_sum(0, 0, 30, 20), 123 * 16 * 600);
    }
}
