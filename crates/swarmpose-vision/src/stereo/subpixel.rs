//! Sub-pixel disparity: SSD block matching around an integer disparity along the same
//! row, then a parabola through the best cost and its two neighbours.

use crate::features::GrayView;
use crate::image::sample_patch;
use sums::{window_sums, window_sums_fixed};

/// The `(2 r + 1)²` window centred on left pixel `(xl, y)` of a rectified pair, with the
/// right image it is matched in (same rows, shifted left by the disparity).
#[derive(Debug, Clone, Copy)]
pub struct PairWindow<'a> {
    /// The left image.
    pub left: GrayView<'a>,
    /// The right image.
    pub right: GrayView<'a>,
    /// Column of the window's centre in the left image, pixels.
    pub xl: usize,
    /// Row of the window's centre, pixels.
    pub y: usize,
    /// Half side of the window, pixels.
    pub r: usize,
}

impl PairWindow<'_> {
    /// Whether the left window, and its rows in the right image, lie inside the images.
    fn rows_inside(&self) -> bool {
        let (y, r) = (self.y, self.r);
        y >= r
            && y + r < self.left.height
            && y + r < self.right.height
            && self.xl >= r
            && self.xl + r < self.left.width
    }
}

/// Sum of squared differences between the window and the one at right `(xr, y)`. The
/// caller keeps both windows inside.
#[inline(always)]
fn ssd(window: PairWindow<'_>, xr: usize) -> u32 {
    let (left, right, xl, y, r) = (window.left, window.right, window.xl, window.y, window.r);
    let mut s = 0u32;
    for yy in y - r..=y + r {
        let lrow = &left.data[yy * left.width + xl - r..=yy * left.width + xl + r];
        let rrow = &right.data[yy * right.width + xr - r..=yy * right.width + xr + r];
        for (a, b) in lrow.iter().zip(rrow) {
            let d = i32::from(*a) - i32::from(*b);
            s += (d * d) as u32;
        }
    }
    s
}

/// Lanes of [`ssd_fixed`]'s rows.
const SSD_LANES: usize = 8;

/// [`ssd`] for a window side `N ≤ SSD_LANES` known to the compiler (`N = 2 r + 1`): rows
/// read as [`SSD_LANES`] pixels, whose squared differences (integers, exact in any order,
/// wrapping) the compiler sums in vector registers, all of them: those past the window's
/// row are then subtracted (a mask on the lanes let the compiler drop lanes and sum the
/// rest pixel by pixel); [`ssd`] where the last row has no pixels past it. The caller
/// keeps both windows inside.
#[inline(always)]
fn ssd_fixed<const N: usize>(window: PairWindow<'_>, xr: usize) -> u32 {
    const { assert!(N <= SSD_LANES) };
    let (left, right, xl, y, r) = (window.left, window.right, window.xl, window.y, window.r);
    if (y + r) * left.width + xl - r + SSD_LANES > left.data.len()
        || (y + r) * right.width + xr - r + SSD_LANES > right.data.len()
    {
        return ssd(window, xr);
    }
    let (mut sums, mut past) = ([0u32; SSD_LANES], 0u32);
    for yy in y - r..=y + r {
        let lrow = &left.data[yy * left.width + xl - r..][..SSD_LANES];
        let rrow = &right.data[yy * right.width + xr - r..][..SSD_LANES];
        for k in 0..SSD_LANES {
            let d = i32::from(lrow[k]) - i32::from(rrow[k]);
            sums[k] = sums[k].wrapping_add((d * d) as u32);
        }
        for k in N..SSD_LANES {
            let d = i32::from(lrow[k]) - i32::from(rrow[k]);
            past = past.wrapping_add((d * d) as u32);
        }
    }
    sums.iter()
        .fold(0u32, |s, &v| s.wrapping_add(v))
        .wrapping_sub(past)
}

/// Refines the disparity of left pixel `(xl, y)` (integers) near `d0` pixels: the SSD of
/// a `(2 r + 1)²` window is evaluated for integer disparities `d0 - search ..= d0 +
/// search`, and a parabola through the minimum and its neighbours gives the sub-pixel
/// offset. `None` when a window leaves an image or the minimum is at the search edge.
#[must_use]
#[inline(always)]
pub fn refine_disparity(window: PairWindow<'_>, d0: i64, search: i64) -> Option<f32> {
    if !window.rows_inside() {
        return None;
    }
    let (xl, r) = (window.xl, window.r);
    let lo = d0 - search - 1;
    let hi = d0 + search + 1;
    // Right column xl - d must keep its window inside.
    if (xl as i64 - hi) < r as i64
        || (xl as i64 - lo) + r as i64 >= window.right.width as i64
        || lo < 0
    {
        return None;
    }
    let mut best = (u32::MAX, 0i64);
    let mut costs = [0u32; 16];
    let n = (hi - lo + 1) as usize;
    if n > costs.len() {
        return None;
    }
    for (k, d) in (lo..=hi).enumerate() {
        let xr = (xl as i64 - d) as usize;
        let c = if r == 3 {
            ssd_fixed::<7>(window, xr)
        } else {
            ssd(window, xr)
        };
        costs[k] = c;
        if c < best.0 && d > lo && d < hi {
            best = (c, d);
        }
    }
    let k = (best.1 - lo) as usize;
    let (cm, c0, cp) = (
        f64::from(costs[k - 1]),
        f64::from(costs[k]),
        f64::from(costs[k + 1]),
    );
    // Edge of the search range: the true minimum may lie outside.
    if best.1 == lo + 1 && cm <= c0 || best.1 == hi - 1 && cp <= c0 {
        return None;
    }
    let denom = cm - 2.0 * c0 + cp;
    let offset = if denom > 0.0 {
        (0.5 * (cm - cp) / denom).clamp(-0.5, 0.5)
    } else {
        0.0
    };
    Some((best.1 as f64 + offset) as f32)
}

/// Gauss-Newton (1D Lucas-Kanade) refinement of a disparity: minimises
/// `Σ (L(x, y) - R(x - d, y))²` over the `(2 r + 1)²` window at left `(xl, y)`, sampling
/// the right image bilinearly with central-difference gradients, starting from `d0`
/// pixels. Unlike a parabola through integer costs it has no pull towards integers.
/// `None` when a window leaves the image, the texture has no horizontal gradient, or
/// the estimate moves more than one pixel from `d0`.
#[must_use]
#[inline(always)]
pub fn refine_disparity_lk(window: PairWindow<'_>, d0: f32, iterations: usize) -> Option<f32> {
    if !window.rows_inside() {
        return None;
    }
    let PairWindow {
        left,
        right,
        xl,
        y,
        r,
    } = window;
    gauss_newton_disparity(right.width, xl, r, d0, iterations, |d| {
        let (mut eg, mut gg) = (0f32, 0f32);
        for yy in y - r..=y + r {
            let lrow = &left.data[yy * left.width..(yy + 1) * left.width];
            let rrow = &right.data[yy * right.width..(yy + 1) * right.width];
            let at = |x: f32| {
                // Through i32, whose conversions are cheaper: x is in [0, width) (the
                // check above; a NaN gives 0 either way), so the same integer.
                let t = x as i32;
                let f = x - t as f32;
                let i = t.unsigned_abs() as usize;
                f32::from(rrow[i]) * (1.0 - f) + f32::from(rrow[i + 1]) * f
            };
            for (xx, &lv) in lrow.iter().enumerate().take(xl + r + 1).skip(xl - r) {
                let xr = xx as f32 - d;
                let (xp, xm) = (xr + 1.0, xr - 1.0);
                let t = xr as i32;
                // When xr ± 1 are exact (the differences below are exact for xr ≥ 1,
                // by Sterbenz), the three samples share the pixel pair and the fraction
                // (x − trunc(x) is exact): the same values from 4 pixels and one
                // conversion.
                let (c, p, m) = if t >= 1 && xp - xr == 1.0 && xr - xm == 1.0 {
                    let f = xr - t as f32;
                    let i = t.unsigned_abs() as usize;
                    let v = &rrow[i - 1..=i + 2];
                    let (v0, v1, v2, v3) = (
                        f32::from(v[0]),
                        f32::from(v[1]),
                        f32::from(v[2]),
                        f32::from(v[3]),
                    );
                    let g = 1.0 - f;
                    (v1 * g + v2 * f, v2 * g + v3 * f, v0 * g + v1 * f)
                } else {
                    (at(xr), at(xp), at(xm))
                };
                let e = f32::from(lv) - c;
                let g = 0.5 * (p - m);
                eg += e * g;
                gg += g * g;
            }
        }
        (eg, gg)
    })
}

/// The Gauss-Newton loop of [`refine_disparity_lk`] from `d0` pixels, `sums(d)` giving
/// `(Σ e g, Σ g²)` over the window at disparity `d` (residual `e`, gradient `g` of the
/// right image). `None` when the right window leaves the image (`right_width` pixels),
/// `Σ g²` is too small, or `d` moves more than one pixel from `d0`.
#[inline(always)]
fn gauss_newton_disparity(
    right_width: usize,
    xl: usize,
    r: usize,
    d0: f32,
    iterations: usize,
    mut sums: impl FnMut(f32) -> (f32, f32),
) -> Option<f32> {
    let mut d = d0;
    for _ in 0..iterations {
        let x0 = xl as f32 - d - r as f32 - 1.0;
        let x1 = xl as f32 - d + r as f32 + 1.0;
        if x0 < 0.0 || x1 + 1.0 >= right_width as f32 {
            return None;
        }
        let (eg, gg) = sums(d);
        if gg < 1e-3 {
            return None;
        }
        let step = -eg / gg;
        d += step;
        if (d - d0).abs() > 1.0 {
            return None;
        }
        if step.abs() < 1e-3 {
            break;
        }
    }
    Some(d)
}

/// Gauss-Newton (2D Lucas-Kanade) refinement of a disparity together with the vertical
/// offset of the right image: minimises `Σ (L(x, y) - R(x - d, y + dy))²` over the
/// `(2 r + 1)²` window at left `(xl, y)`, from `(d0, 0)`. Returns `(d, dy)` pixels.
/// `None` near the borders, on texture that does not fix both, when `d` moves more
/// than one pixel from `d0` or `dy` more than two.
#[must_use]
#[inline(always)]
pub fn refine_disparity_lk_2d(
    window: PairWindow<'_>,
    d0: f32,
    iterations: usize,
) -> Option<(f32, f32)> {
    align_window(window, d0, iterations, true)
}

/// Vertical offset, pixels, of the right image against the left around left pixel
/// `(xl, y)` for a known disparity `d` (pixels): Gauss-Newton on
/// `Σ (L(x, y) - R(x - d, y + dy))²` over the `(2 r + 1)²` window. Zero on a perfectly
/// rectified pair; used to check rectification. `None` near the borders, on texture
/// without vertical gradient, or beyond 2 pixels.
#[must_use]
#[inline(always)]
pub fn row_offset(window: PairWindow<'_>, d: f32) -> Option<f32> {
    align_window(window, d, 10, false).map(|(_, dy)| dy)
}

/// Gauss-Newton on `Σ (L(x, y) - R(x - d, y + dy))²` over the `(2 r + 1)²` window at left
/// `(xl, y)`, from `(d0, 0)`: `dy` alone, or `d` too when `disparity_free`. Returns
/// `(d, dy)`; `None` near the borders, on texture that does not fix the unknowns, when
/// `d` moves more than one pixel or `dy` more than two.
#[inline(always)]
fn align_window(
    window: PairWindow<'_>,
    d0: f32,
    iterations: usize,
    disparity_free: bool,
) -> Option<(f32, f32)> {
    let PairWindow {
        left,
        right,
        xl,
        y,
        r,
    } = window;
    const MAX_SIDE: usize = 13;
    let n = 2 * r + 1;
    let m = n + 2;
    if m > MAX_SIDE
        || y < r + 4
        || y + r + 4 >= left.height.min(right.height)
        || xl < r
        || xl + r >= left.width
    {
        return None;
    }
    // The left window, and the right one with a row and a column around it for the
    // gradients.
    let mut lw = [0f32; MAX_SIDE * MAX_SIDE];
    for (out, yy) in lw.chunks_exact_mut(n).zip(y - r..=y + r) {
        let row = &left.data[yy * left.width + xl - r..][..n];
        for (o, &v) in out.iter_mut().zip(row) {
            *o = f32::from(v);
        }
    }
    // The same with the right window's stride (for `window_sums_fixed`).
    let mut lws = [0f32; MAX_SIDE * MAX_SIDE];
    for (out, row) in lws.chunks_exact_mut(m).zip(lw.chunks_exact(n).take(n)) {
        out[..n].copy_from_slice(row);
    }
    let mut rw = [0f32; MAX_SIDE * MAX_SIDE];
    let mut products = [[0f32; 7 * 9 - 2]; 5];
    let (mut d, mut dy) = (d0, 0f32);
    for _ in 0..iterations {
        sample_patch(
            right,
            xl as f32 - d - r as f32 - 1.0,
            y as f32 + dy - r as f32 - 1.0,
            m,
            &mut rw,
        )?;
        // The derivatives of e = L - R(x - d, y + dy): gx by d, gy by dy; the side of
        // the default radius (3) with its length known to the compiler.
        let [a, b, c, ex, ey] = if n == 7 {
            window_sums_fixed::<7, { 7 * 9 - 2 }>(&lws, &rw, &mut products, disparity_free)
        } else {
            window_sums(&lw, &rw, n, disparity_free)
        };
        // Steps -(JᵀJ)⁻¹ Jᵀ e, when the texture fixes them (a NaN fails too).
        let (sd, sy) = if disparity_free {
            let det = a * c - b * b;
            let determined = det > 1e-6 * (a * c).max(1e-3) && a >= 1e-3;
            if !determined {
                return None;
            }
            (-(c * ex - b * ey) / det, -(a * ey - b * ex) / det)
        } else {
            if c < 1e-3 {
                return None;
            }
            (0.0, -ey / c)
        };
        d += sd;
        dy += sy;
        if (d - d0).abs() > 1.0 || dy.abs() > 2.0 {
            return None;
        }
        if sd.abs() < 1e-3 && sy.abs() < 1e-3 {
            break;
        }
    }
    Some((d, dy))
}

mod sums;
#[cfg(test)]
mod window_bits;

#[cfg(test)]
mod tests {
    use super::*;

    /// A `w x h` pair of 8-bit images of the pattern `f(x, y)`, the right one shifted so
    /// that `R(x - d, y + dy) = L(x, y)`.
    fn shifted_pair(
        (w, h): (usize, usize),
        f: impl Fn(f32, f32) -> f32,
        d: f32,
        dy: f32,
    ) -> (Vec<u8>, Vec<u8>) {
        let at = |i: usize, shift: (f32, f32)| {
            f((i % w) as f32 + shift.0, (i / w) as f32 + shift.1).round() as u8
        };
        (
            (0..w * h).map(|i| at(i, (0.0, 0.0))).collect(),
            (0..w * h).map(|i| at(i, (d, -dy))).collect(),
        )
    }

    /// The 7 x 7 window at left pixel `(xl, y)` of a pair of `w x h` images.
    fn window<'a>(
        (w, h): (usize, usize),
        (left, right): (&'a [u8], &'a [u8]),
        (xl, y): (usize, usize),
    ) -> PairWindow<'a> {
        let view = |data| GrayView {
            width: w,
            height: h,
            data,
        };
        PairWindow {
            left: view(left),
            right: view(right),
            xl,
            y,
            r: 3,
        }
    }

    /// A smooth horizontal pattern shifted by a known sub-pixel disparity.
    #[test]
    fn sub_pixel_shift_is_recovered() {
        let (w, h) = (80, 20);
        let f = |x: f32, _: f32| 128.0 + 60.0 * (x * 0.45).sin() + 30.0 * (x * 0.17 + 1.0).cos();
        for &true_d in &[10.0f32, 10.3, 10.5, 10.75] {
            let (left, right) = shifted_pair((w, h), f, true_d, 0.0);
            let at = window((w, h), (&left, &right), (40, 10));
            let p = refine_disparity(at, 10, 2).expect("parabola");
            let d = refine_disparity_lk(at, p, 8).expect("lk");
            assert!((d - true_d).abs() < 0.05, "{true_d}: parabola {p}, lk {d}");
        }
    }

    /// The sums of [`refine_disparity_lk`] with every sample taken on its own, as defined.
    fn lk_by_definition(window: PairWindow<'_>, d0: f32) -> Option<f32> {
        let PairWindow {
            left,
            right,
            xl,
            y,
            r,
        } = window;
        gauss_newton_disparity(right.width, xl, r, d0, 8, |d| {
            let (mut eg, mut gg) = (0f32, 0f32);
            for yy in y - r..=y + r {
                let rrow = &right.data[yy * right.width..(yy + 1) * right.width];
                let at = |x: f32| {
                    let i = x as usize;
                    let f = x - i as f32;
                    f32::from(rrow[i]) * (1.0 - f) + f32::from(rrow[i + 1]) * f
                };
                for xx in xl - r..=xl + r {
                    let xr = xx as f32 - d;
                    let e = f32::from(left.data[yy * left.width + xx]) - at(xr);
                    let g = 0.5 * (at(xr + 1.0) - at(xr - 1.0));
                    eg += e * g;
                    gg += g * g;
                }
            }
            (eg, gg)
        })
    }

    /// Bit for bit the definition, also where `x − d ± 1` round (next to powers of two).
    #[test]
    fn gauss_newton_disparity_is_the_definition() {
        let (w, h) = (1100usize, 9usize);
        let mut g = crate::test_noise::Lcg(3);
        let mut noise = || (g.next_u32() >> 28) as f32;
        let f = |x: f32| 128.0 + 60.0 * (x * 0.45).sin() + 30.0 * (x * 0.17 + 1.0).cos();
        let left: Vec<u8> = (0..w * h)
            .map(|i| (f((i % w) as f32) + noise()).round() as u8)
            .collect();
        let right: Vec<u8> = (0..w * h)
            .map(|i| (f((i % w) as f32 + 7.3) + noise()).round() as u8)
            .collect();
        let mut found = 0;
        for xl in (5..w - 5)
            .step_by(3)
            .chain([12, 13, 20, 21, 36, 37, 68, 69, 1031, 1032])
        {
            for d0 in [
                0.3f32,
                7.3,
                7.000_001,
                8.999_999,
                2.0 - 1e-6,
                1.5,
                xl as f32 - 4.000_000_5,
            ] {
                let at = window((w, h), (&left, &right), (xl, 4));
                let got = refine_disparity_lk(at, d0, 8);
                assert_eq!(
                    got.map(f32::to_bits),
                    lk_by_definition(at, d0).map(f32::to_bits),
                    "xl {xl}, d0 {d0}"
                );
                found += usize::from(got.is_some());
            }
        }
        assert!(found > 500, "{found}");
    }

    /// A 2D pattern whose right image is shifted by a disparity and a known row offset.
    #[test]
    fn row_offset_is_measured() {
        let (w, h) = (80usize, 40usize);
        let f = |x: f32, y: f32| {
            128.0 + 50.0 * (x * 0.37).sin() * (y * 0.29).cos() + 30.0 * ((x + 2.0 * y) * 0.13).sin()
        };
        for &true_dy in &[0.0f32, 0.3, -0.45, 1.1] {
            let (left, right) = shifted_pair((w, h), f, 7.0, true_dy);
            let dy = row_offset(window((w, h), (&left, &right), (40, 20)), 7.0).expect("measured");
            assert!((dy - true_dy).abs() < 0.05, "{true_dy}: {dy}");
        }
    }

    /// Oblique texture, the right image shifted by a disparity and a row offset: the 1D
    /// refinement along the row is pulled off by the row offset times the slant, the 2D
    /// one recovers both.
    #[test]
    fn disparity_with_a_row_offset_is_recovered_in_2d() {
        let (w, h) = (80usize, 40usize);
        // Stripes slanted at 45 degrees plus a weaker pattern, so both directions are fixed.
        let f = |x: f32, y: f32| {
            128.0 + 60.0 * ((x + y) * 0.5).sin() + 20.0 * (x * 0.31).cos() * (y * 0.23).sin()
        };
        for &(true_d, true_dy) in &[(7.0f32, 0.0f32), (7.3, 0.5), (6.8, -0.6), (7.5, 1.0)] {
            let (left, right) = shifted_pair((w, h), f, true_d, true_dy);
            let at = window((w, h), (&left, &right), (40, 20));
            let (d, dy) = refine_disparity_lk_2d(at, 7.0, 10).expect("2d");
            assert!(
                (d - true_d).abs() < 0.05 && (dy - true_dy).abs() < 0.05,
                "({true_d}, {true_dy}): ({d}, {dy})"
            );
            if true_dy.abs() >= 0.5 {
                let d1 = refine_disparity_lk(at, 7.0, 10).unwrap_or(f32::NAN);
                assert!(
                    (d1 - true_d).abs() >= 0.2 || d1.is_nan(),
                    "the row alone should be pulled off: {d1} against {true_d}"
                );
            }
        }
    }
}
