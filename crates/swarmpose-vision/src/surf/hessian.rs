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
use super::refine::{refine, refine_finest};
use super::response::{Block, Detection, ResponseLayer, is_local_max};

/// Filter size `L` of layer `layer` (0-based, `0..intervals + 2`) in octave `octave`:
/// `3 · (2^(octave+1) · (layer + 1) + 1)`.
#[must_use]
pub(crate) fn filter_size(octave: usize, layer: usize) -> usize {
    3 * ((2usize << octave) * (layer + 1) + 1)
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::GrayView;
    use crate::surf::test_images::gaussian_blob;

    /// The scale-space maxima of `det(H_approx)` above the threshold over all octaves of
    /// one integral image (no per-octave smoothing).
    fn detect(integral: &IntegralImage, octaves: usize, search: Search) -> Vec<Detection> {
        let (mut layers, mut out) = (Vec::new(), Vec::new());
        for octave in 0..octaves {
            if !detect_octave(integral, octave, search, &mut layers, &mut out) {
                break;
            }
        }
        out
    }

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
        let found = detect(&ii, 2, search(false));
        assert!(!found.iter().any(near), "{found:?}");
        let found = detect(&ii, 2, search(true));
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
            let search = Search {
                intervals: 2,
                initial_step: 1,
                threshold: 1e-4,
                finest_layer: false,
            };
            let found = detect(&ii, 4, search);
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
