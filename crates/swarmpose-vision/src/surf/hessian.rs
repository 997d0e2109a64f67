//! Fast-Hessian detector: box-filter approximations of the Hessian over octaves and
//! scales, 3×3×3 non-maximum suppression and quadratic sub-pixel/sub-scale refinement.
//!
//! At a point `x` and scale `σ` the Hessian of the Gaussian-smoothed image is
//!
//! ```text
//! H(x, σ) = | Lxx  Lxy |
//!           | Lxy  Lyy |,   Lab = ∂²(G_σ ∗ I)/∂a∂b.
//! ```
//!
//! SURF replaces the second-order Gaussian derivatives by box filters of size `L × L`
//! (`L = 9` approximates `σ = 1.2`, so `σ = 1.2 · L / 9`), evaluated in constant time on
//! the integral image. With lobe length `l = L / 3`:
//!
//! * `Dyy`: three stacked `(2l − 1) × l` lobes weighted `+1, −2, +1` (`Dxx` transposed);
//! * `Dxy`: four `l × l` lobes in the quadrants around the centre, `+1` where `x·y > 0`
//!   and `−1` elsewhere, separated by a one-pixel cross.
//!
//! Responses are divided by the filter area `L²` (and intensities by the white level, 255
//! for 8-bit images) so that they are comparable across scales, and the blob response is the approximated determinant
//!
//! ```text
//! det(H_approx) = Dxx · Dyy − (0.9 · Dxy)²,
//! ```
//!
//! where 0.9 ≈ ‖Lxy‖_F ‖Dyy‖_F / (‖Lyy‖_F ‖Dxy‖_F) balances the box approximation. The
//! sign of the trace `Dxx + Dyy` (the Laplacian) tells bright blobs on a dark background
//! (negative) from dark blobs on a bright one (positive).
//!
//! The box filters are not Gaussian derivatives: `Dyy` changes sign at `±L/6` where
//! `∂²G_σ/∂y²` does at `±σ = ±0.133 L`. As a consequence, with the area normalisation, an
//! isotropic Gaussian blob of standard deviation `σ_b` gives its strongest response at
//! `L ≈ 5.04 σ_b` (computed in closed form with error functions for the continuous
//! filters, and observed on sampled blobs), i.e. at `s = 1.2 L / 9 ≈ 0.67 σ_b` rather than
//! at `s = σ_b` as scale-normalised Gaussian derivatives would. Scale covariance is
//! unaffected: the factor is the same at every scale.
//!
//! Octave `o` (from 0) holds `intervals + 2` filters of sizes
//! `L(o, i) = 3 · (2^(o+1) · (i + 1) + 1)` — 9, 15, 21, 27; 15, 27, 39, 51; 27, 51, 75, 99;
//! … — sampled every `step · 2^o` pixels. Maxima are searched in the inner `intervals`
//! layers of each octave and refined by [`super::refine`], and optionally in the finest
//! layer of octave 0 (see [`detect_octave`]).
//!
//! The geometry was checked for half-pixel shifts: every filter size is odd and each box
//! is symmetric about the centre pixel `r = (L − 1) / 2` of the window, so sample
//! `(c, r)` is the pixel `(c · step, r · step)` exactly, and [`super::refine`] converts
//! its offsets by the sampling step (positions) and by the filter spacing of the octave
//! (scale).

use super::integral::IntegralImage;
use super::refine::{Block, refine, refine_finest};

/// Filter size `L` of layer `layer` (0-based, `0..intervals + 2`) in octave `octave`:
/// `3 · (2^(octave+1) · (layer + 1) + 1)`.
#[must_use]
pub(crate) fn filter_size(octave: usize, layer: usize) -> usize {
    3 * ((2usize << octave) * (layer + 1) + 1)
}

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
    fn valid_range(&self, extent: usize) -> Option<(usize, usize)> {
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

/// What [`detect_octave`] searches.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Search {
    /// Scale layers searched per octave.
    pub intervals: usize,
    /// Sampling step of octave 0, pixels.
    pub initial_step: usize,
    /// Minimum response.
    pub threshold: f32,
    /// Also keep maxima of the finest layer of octave 0 (see [`detect_octave`]).
    pub finest_layer: bool,
}

/// Detects scale-space maxima of `det(H_approx)` above the threshold over all octaves of
/// one integral image (no per-octave smoothing) and appends them to `out`.
#[cfg(test)]
pub(crate) fn detect(
    integral: &IntegralImage,
    octaves: usize,
    search: Search,
    layers: &mut Vec<ResponseLayer>,
    out: &mut Vec<Detection>,
) {
    for octave in 0..octaves {
        if !detect_octave(integral, octave, search, layers, out) {
            break;
        }
    }
}

/// Detects the maxima of octave `octave` in `integral` (the image as smoothed for that
/// octave) and appends them to `out`; `layers` is scratch space reused across octaves
/// (and calls). Returns `false` when the octave's filters do not fit in the image (nor
/// will those of any later octave).
///
/// A maximum is a sample of an inner layer strictly above its 26 neighbours in the
/// 3×3×3 block of (column, row, layer). With `search.finest_layer`, the finest layer of
/// octave 0 (filter 9), which has no layer below it, also yields its samples strictly
/// above their 8 neighbours in that layer and the 9 nearest samples of the next layer
/// (filter 15): structures finer than the smallest searched scale, which would
/// otherwise not be detected at all. They keep the scale `s = 1.2` of the filter.
pub(crate) fn detect_octave(
    integral: &IntegralImage,
    octave: usize,
    search: Search,
    layers: &mut Vec<ResponseLayer>,
    out: &mut Vec<Detection>,
) -> bool {
    let Search {
        intervals,
        initial_step,
        threshold,
        finest_layer,
    } = search;
    let per_octave = intervals + 2;
    if layers.len() < per_octave {
        layers.resize_with(per_octave, ResponseLayer::default);
    }
    let (w, h) = (integral.width(), integral.height());
    if !octave_fits(w, h, octave, search) {
        return false;
    }
    let step = initial_step.max(1) << octave;
    for (layer, slot) in layers.iter_mut().take(per_octave).enumerate() {
        slot.compute(integral, filter_size(octave, layer), step);
    }
    // The largest filter bounds where all three scales of a 3×3×3 block exist.
    let (Some((c_lo, c_hi)), Some((r_lo, r_hi))) = (
        layers[per_octave - 1].valid_range(w),
        layers[per_octave - 1].valid_range(h),
    ) else {
        return false;
    };
    if c_hi < c_lo + 2 || r_hi < r_lo + 2 {
        return false;
    }
    let layers = &layers[..per_octave];
    if octave == 0 && finest_layer {
        let (finest, next) = (&layers[0], &layers[1]);
        for row in r_lo + 1..r_hi {
            for col in c_lo + 1..c_hi {
                let v = finest.at(col, row);
                if v > threshold && is_finest_max(v, finest, next, col, row) {
                    out.push(refine_finest(finest, col, row));
                }
            }
        }
    }
    let bounds = Block {
        mid: intervals,
        col: c_hi - 1,
        row: r_hi - 1,
    };
    let lower = Block {
        mid: 1,
        col: c_lo + 1,
        row: r_lo + 1,
    };
    for mid in 1..=intervals {
        let (below, centre, above) = (&layers[mid - 1], &layers[mid], &layers[mid + 1]);
        for row in r_lo + 1..r_hi {
            for col in c_lo + 1..c_hi {
                let v = centre.at(col, row);
                if v <= threshold || !is_local_max(v, below, centre, above, col, row) {
                    continue;
                }
                let block = Block { mid, col, row };
                if let Some(d) = refine(layers, block, lower, bounds, octave) {
                    out.push(d);
                }
            }
        }
    }
    true
}

/// True when the filters of octave `octave` fit in a `w × h` image with room for a
/// 3×3 block of samples.
pub(crate) fn octave_fits(w: usize, h: usize, octave: usize, search: Search) -> bool {
    if octave >= 24 {
        return false;
    }
    let step = search.initial_step.max(1) << octave;
    let top = filter_size(octave, search.intervals + 1);
    top + 2 * step <= w && top + 2 * step <= h
}

/// True when `v = finest(col, row)` is strictly larger than its 8 neighbours in `finest`
/// and the 9 samples around `(col, row)` in `next` (same grid).
fn is_finest_max(
    v: f32,
    finest: &ResponseLayer,
    next: &ResponseLayer,
    col: usize,
    row: usize,
) -> bool {
    for rr in row - 1..=row + 1 {
        for cc in col - 1..=col + 1 {
            if next.at(cc, rr) >= v || ((rr, cc) != (row, col) && finest.at(cc, rr) >= v) {
                return false;
            }
        }
    }
    true
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::GrayView;
    use crate::surf::test_images::gaussian_blob;

    #[test]
    fn filter_sizes_follow_the_paper() {
        let sizes = |o| (0..4).map(|i| filter_size(o, i)).collect::<Vec<_>>();
        assert_eq!(sizes(0), [9, 15, 21, 27]);
        assert_eq!(sizes(1), [15, 27, 39, 51]);
        assert_eq!(sizes(2), [27, 51, 75, 99]);
        assert_eq!(sizes(3), [51, 99, 147, 195]);
    }

    /// `det(H_approx)` at the image centre for filter size `filter`.
    fn centre_response(img: &[u8], n: usize, filter: usize) -> (f32, bool) {
        let ii = IntegralImage::new(GrayView {
            width: n,
            height: n,
            data: img,
        });
        let mut layer = ResponseLayer::default();
        layer.compute(&ii, filter, 1);
        let i = (n / 2) * layer.cols + n / 2;
        (layer.det[i], layer.laplacian_positive[i])
    }

    #[test]
    fn blob_response_peaks_near_the_matching_filter_size() {
        let n = 161;
        for sigma in [2.5f32, 4.0, 6.0] {
            let img = gaussian_blob(n, n, sigma, true);
            let (best, _) = (9..=99)
                .step_by(6)
                .map(|f| (f, centre_response(&img, n, f).0))
                .fold((0, f32::MIN), |a, b| if b.1 > a.1 { b } else { a });
            // The continuous box filters peak at L = 5.04 σ (s = 0.67 σ); the grid of
            // sizes is 6 pixels apart.
            let predicted = 5.04 * sigma;
            assert!(
                (best as f32 - predicted).abs() <= 3.5,
                "sigma {sigma}: peak at L = {best}, box-filter prediction {predicted}"
            );
            // The Gaussian-derivative rule L = 9σ / 1.2 overestimates it by a third.
            let gaussian_rule = sigma * 9.0 / 1.2;
            assert!(best as f32 > 0.6 * gaussian_rule && (best as f32) < gaussian_rule);
        }
    }

    #[test]
    fn laplacian_sign_tells_dark_from_bright_blobs() {
        let n = 81;
        let (det_bright, lap_bright) = centre_response(&gaussian_blob(n, n, 3.0, true), n, 21);
        let (det_dark, lap_dark) = centre_response(&gaussian_blob(n, n, 3.0, false), n, 21);
        assert!(det_bright > 0.0 && det_dark > 0.0);
        assert!(!lap_bright, "bright blob: negative trace");
        assert!(lap_dark, "dark blob: positive trace");
    }

    #[test]
    fn blobs_finer_than_the_second_filter_need_the_finest_layer() {
        // A blob of sigma 1.2 peaks at L ≈ 6, below the finest filter: the paper's search
        // (inner layers only) misses it, the finest-layer search finds it at s = 1.2.
        let n = 81;
        let img = gaussian_blob(n, n, 1.2, false);
        let ii = IntegralImage::new(GrayView {
            width: n,
            height: n,
            data: &img,
        });
        let search = |finest_layer| Search {
            intervals: 2,
            initial_step: 1,
            threshold: 1e-3,
            finest_layer,
        };
        let c = (n / 2) as f32;
        let near = |d: &Detection| (d.x - c).abs() < 1.0 && (d.y - c).abs() < 1.0;
        let mut found = Vec::new();
        detect(&ii, 2, search(false), &mut Vec::new(), &mut found);
        assert!(!found.iter().any(near), "{found:?}");
        detect(&ii, 2, search(true), &mut Vec::new(), &mut found);
        let hit = found.iter().find(|d| near(d));
        assert!(
            hit.is_some_and(|d| d.scale == 1.2 && d.laplacian_positive),
            "{found:?}"
        );
    }

    #[test]
    fn detector_finds_a_blob_at_its_position_and_scale() {
        let n = 161;
        for sigma in [3.0f32, 5.0] {
            let img = gaussian_blob(n, n, sigma, false);
            let ii = IntegralImage::new(GrayView {
                width: n,
                height: n,
                data: &img,
            });
            let mut found = Vec::new();
            let search = Search {
                intervals: 2,
                initial_step: 1,
                threshold: 1e-4,
                finest_layer: false,
            };
            detect(&ii, 4, search, &mut Vec::new(), &mut found);
            let best = found
                .iter()
                .max_by(|a, b| a.response.total_cmp(&b.response))
                .copied();
            let Some(best) = best else {
                panic!("no detection for sigma {sigma}");
            };
            let c = (n / 2) as f32;
            assert!(
                (best.x - c).abs() < 1.0 && (best.y - c).abs() < 1.0,
                "{best:?}"
            );
            // s = 1.2 L / 9 at the peak L ≈ 5.04 σ: s ≈ 0.67 σ.
            assert!(
                (best.scale / (0.672 * sigma) - 1.0).abs() < 0.2,
                "sigma {sigma}: {best:?}"
            );
            assert!(best.laplacian_positive);
        }
    }
}
