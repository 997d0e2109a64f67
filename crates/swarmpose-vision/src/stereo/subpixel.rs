//! Sub-pixel disparity: SSD block matching around an integer disparity along the same
//! row, then a parabola through the best cost and its two neighbours.

use crate::features::GrayView;

/// Sum of squared differences between the `(2 r + 1)²` window at left `(xl, y)` and at
/// right `(xr, y)`. The caller keeps both windows inside.
#[inline]
fn ssd(left: GrayView<'_>, right: GrayView<'_>, xl: usize, xr: usize, y: usize, r: usize) -> u32 {
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

/// Refines the disparity of left pixel `(xl, y)` (integers) near `d0` pixels: the SSD of
/// a `(2 r + 1)²` window is evaluated for integer disparities `d0 - search ..= d0 +
/// search`, and a parabola through the minimum and its neighbours gives the sub-pixel
/// offset. `None` when a window leaves an image or the minimum is at the search edge.
#[must_use]
pub fn refine_disparity(
    left: GrayView<'_>,
    right: GrayView<'_>,
    xl: usize,
    y: usize,
    d0: i64,
    search: i64,
    r: usize,
) -> Option<f32> {
    if y < r || y + r >= left.height || y + r >= right.height || xl < r || xl + r >= left.width {
        return None;
    }
    let lo = d0 - search - 1;
    let hi = d0 + search + 1;
    // Right column xl - d must keep its window inside.
    if (xl as i64 - hi) < r as i64 || (xl as i64 - lo) + r as i64 >= right.width as i64 || lo < 0 {
        return None;
    }
    let mut best = (u32::MAX, 0i64);
    let mut costs = [0u32; 16];
    let n = (hi - lo + 1) as usize;
    if n > costs.len() {
        return None;
    }
    for (k, d) in (lo..=hi).enumerate() {
        let c = ssd(left, right, xl, (xl as i64 - d) as usize, y, r);
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
