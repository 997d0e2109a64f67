//! The detector's scale space: one [`ResponseLayer`] of `det(H_approx)` per filter size
//! (see [`super::hessian`] for the box filters), the 3×3×3 [`Block`] a maximum is searched
//! and refined in, and a refined [`Detection`]. The detector ([`super::hessian`]) and the
//! refinement ([`super::refine`]) both build on these.

use super::integral::IntegralImage;

/// One scale of the detector: `det(H_approx)` and the Laplacian sign on a sampling grid.
#[derive(Debug, Clone, Default)]
pub(crate) struct ResponseLayer {
    /// Filter size `L`, pixels.
    pub filter: usize,
    /// Sampling step, pixels: sample `(c, r)` is pixel `(c · step, r · step)`.
    pub step: usize,
    /// Grid columns.
    pub cols: usize,
    /// Grid rows.
    pub rows: usize,
    /// Row-major `det(H_approx)`; 0 where the filter does not fit inside the image.
    pub det: Vec<f32>,
    /// Row-major `Dxx + Dyy > 0`.
    pub laplacian_positive: Vec<bool>,
}

impl ResponseLayer {
    /// Sets the geometry and computes every response.
    pub fn compute(&mut self, integral: &IntegralImage, filter: usize, step: usize) {
        let (w, h) = (integral.width(), integral.height());
        self.filter = filter;
        self.step = step;
        self.cols = w.div_ceil(step);
        self.rows = h.div_ceil(step);
        let n = self.cols * self.rows;
        self.det.clear();
        self.det.resize(n, 0.0);
        self.laplacian_positive.clear();
        self.laplacian_positive.resize(n, false);

        let l = filter / 3;
        let r = (filter - 1) / 2;
        if filter > w || filter > h {
            return;
        }
        let stride = integral.stride();
        let at = |u: usize, v: usize| v * stride + u;
        // Box corners relative to the top-left corner of the filter window.
        let big = 2 * l - 1;
        let yy_whole = (at(r + 1 - l, 0), filter * stride, big);
        let yy_mid = (at(r + 1 - l, r - (l - 1) / 2), l * stride, big);
        let xx_whole = (at(0, r + 1 - l), big * stride, filter);
        let xx_mid = (at(r - (l - 1) / 2, r + 1 - l), big * stride, l);
        let lobe = l * stride;
        let q_tl = at(r - l, r - l);
        let q_tr = at(r + 1, r - l);
        let q_bl = at(r - l, r + 1);
        let q_br = at(r + 1, r + 1);
        let norm = 1.0 / (integral.white() as f32 * (filter * filter) as f32);

        let c_lo = r.div_ceil(step);
        let r_lo = c_lo;
        // Last valid sample: c · step + r ≤ w − 1.
        let c_hi = (w - 1 - r) / step;
        let r_hi = (h - 1 - r) / step;
        if c_hi < c_lo || r_hi < r_lo {
            return;
        }
        let n = c_hi + 1 - c_lo;
        // Row accumulators of the unnormalised box-filter responses (exact integers).
        let (mut dxx, mut dyy, mut dxy) = (vec![0i32; n], vec![0i32; n], vec![0i32; n]);
        let sums = integral.raw();
        for row in r_lo..=r_hi {
            // Top-left corner of the filter window of the first sample of the row.
            let base = (row * step - r) * stride + c_lo * step - r;
            dxx.fill(0);
            dyy.fill(0);
            dxy.fill(0);
            let boxes = |out: &mut [i32], b: (usize, usize, usize), weight: i32| {
                add_box_row(sums, base + b.0, b.1, b.2, step, weight, out);
            };
            boxes(&mut dyy, yy_whole, 1);
            boxes(&mut dyy, yy_mid, -3);
            boxes(&mut dxx, xx_whole, 1);
            boxes(&mut dxx, xx_mid, -3);
            boxes(&mut dxy, (q_tl, lobe, l), 1);
            boxes(&mut dxy, (q_br, lobe, l), 1);
            boxes(&mut dxy, (q_tr, lobe, l), -1);
            boxes(&mut dxy, (q_bl, lobe, l), -1);
            let start = row * self.cols + c_lo;
            let det = &mut self.det[start..start + n];
            let lap = &mut self.laplacian_positive[start..start + n];
            for ((((d, p), &xx), &yy), &xy) in det.iter_mut().zip(lap).zip(&dxx).zip(&dyy).zip(&dxy)
            {
                let (xx, yy, xy) = (xx as f32 * norm, yy as f32 * norm, xy as f32 * norm);
                *d = xx * yy - 0.81 * xy * xy;
                *p = xx + yy > 0.0;
            }
        }
    }

    /// Response at grid position `(col, row)`; the caller keeps it inside the grid.
    #[inline]
    pub(super) fn at(&self, col: usize, row: usize) -> f32 {
        self.det[row * self.cols + col]
    }

    /// Grid range `[lo, hi]` of columns (and rows) where this filter lies inside the
    /// image, or `None` when it fits nowhere.
    pub(super) fn valid_range(&self, extent: usize) -> Option<(usize, usize)> {
        let r = (self.filter - 1) / 2;
        if self.filter > extent {
            return None;
        }
        let lo = r.div_ceil(self.step);
        let hi = (extent - 1 - r) / self.step;
        (lo <= hi).then_some((lo, hi))
    }
}

/// Adds `weight ×` the box sums of `n = out.len()` boxes of `cols` columns and
/// `rows_offset / stride` rows whose top-left table indices are `top_left + i · step`:
/// one box filter term along a row of samples, written as slice zips so that the
/// compiler can drop the bounds checks and vectorise the `step = 1` case.
fn add_box_row(
    sums: &[u32],
    top_left: usize,
    rows_offset: usize,
    cols: usize,
    step: usize,
    weight: i32,
    out: &mut [i32],
) {
    let n = out.len();
    if n == 0 {
        return;
    }
    let span = (n - 1) * step + 1;
    let bottom_left = top_left + rows_offset;
    let a = &sums[top_left..top_left + span];
    let b = &sums[top_left + cols..top_left + cols + span];
    let c = &sums[bottom_left..bottom_left + span];
    let d = &sums[bottom_left + cols..bottom_left + cols + span];
    if step == 1 {
        for ((((o, a), b), c), d) in out.iter_mut().zip(a).zip(b).zip(c).zip(d) {
            *o += weight * d.wrapping_sub(*b).wrapping_sub(*c).wrapping_add(*a) as i32;
        }
    } else {
        let quads = a
            .iter()
            .step_by(step)
            .zip(b.iter().step_by(step))
            .zip(c.iter().step_by(step))
            .zip(d.iter().step_by(step));
        for (o, (((a, b), c), d)) in out.iter_mut().zip(quads) {
            *o += weight * d.wrapping_sub(*b).wrapping_sub(*c).wrapping_add(*a) as i32;
        }
    }
}

/// A refined detection in image coordinates.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Detection {
    /// Column, pixels.
    pub x: f32,
    /// Row, pixels.
    pub y: f32,
    /// `s = 1.2 · L / 9` at the interpolated filter size `L`.
    pub scale: f32,
    /// Interpolated `det(H_approx)`.
    pub response: f32,
    /// `Dxx + Dyy > 0` at the maximum (a dark blob on a brighter background).
    pub laplacian_positive: bool,
    /// Octave of the maximum.
    pub octave: u8,
}

/// The centre of a 3×3×3 block: layer `mid` of the octave, grid `(col, row)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) struct Block {
    /// Layer within the octave.
    pub mid: usize,
    /// Grid column.
    pub col: usize,
    /// Grid row.
    pub row: usize,
}

/// True when `v = centre(col, row)` is strictly larger than its 26 neighbours.
#[inline]
pub(super) fn is_local_max(
    v: f32,
    below: &ResponseLayer,
    centre: &ResponseLayer,
    above: &ResponseLayer,
    col: usize,
    row: usize,
) -> bool {
    for layer in [below, centre, above] {
        for rr in row - 1..=row + 1 {
            for cc in col - 1..=col + 1 {
                let same = std::ptr::eq(layer, centre) && rr == row && cc == col;
                if !same && layer.at(cc, rr) >= v {
                    return false;
                }
            }
        }
    }
    true
}
