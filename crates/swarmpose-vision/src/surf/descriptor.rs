//! The 64-dimensional SURF descriptor (Bay et al. 2008, §4.2).
//!
//! A square window of side `20s` is centred on the keypoint `(x, y)` and rotated to its
//! orientation `θ`. With `(u, v)` the window coordinates (along and across `θ`), the
//! sample points are
//!
//! ```text
//! u, v ∈ {(k − 9.5) · s : k = 0, …, 19},
//! p(u, v) = (x + u cos θ − v sin θ,  y + u sin θ + v cos θ),
//! ```
//!
//! split into 4 × 4 subregions of 5 × 5 samples. At each sample a Haar wavelet of side
//! `2s` gives the image-axis responses `(dx, dy)`, rotated into the window frame and
//! weighted by a Gaussian of `σ = 3.3s` centred on the keypoint:
//!
//! ```text
//! d_u =  dx cos θ + dy sin θ,   d_v = −dx sin θ + dy cos θ,
//! w   = exp(−(u² + v²) / (2 · (3.3s)²)).
//! ```
//!
//! Each subregion contributes `(Σ w·d_u, Σ |w·d_u|, Σ w·d_v, Σ |w·d_v|)` (subregions in
//! row-major order of `(v, u)`), and the 64-vector is scaled to unit Euclidean length,
//! which makes it invariant to contrast. Upright SURF uses `θ = 0`.

use std::sync::LazyLock;

use super::integral::{IntegralImage, haar, nearest_corner};
use crate::features::FloatDescriptor64;

/// Window coordinate of sample `k` in units of `s`: `k − 9.5`.
#[inline]
fn sample_unit(k: usize) -> f32 {
    k as f32 - 9.5
}

/// `exp(−(u² + v²) / (2 · 3.3²))` for the 20 × 20 samples (units of `s`), row-major in
/// `(v, u)`; computed once.
static WEIGHTS: LazyLock<[f32; 400]> = LazyLock::new(|| {
    let mut w = [0.0f32; 400];
    for (i, w) in w.iter_mut().enumerate() {
        let (u, v) = (sample_unit(i % 20), sample_unit(i / 20));
        *w = (-(u * u + v * v) / (2.0 * 3.3 * 3.3)).exp();
    }
    w
});

/// The unit-length descriptor of the keypoint at `(x, y)` with scale `scale` and
/// orientation `angle` (radians); all zeros when the window holds no gradient at all.
#[must_use]
pub(crate) fn describe(
    integral: &IntegralImage,
    x: f32,
    y: f32,
    scale: f32,
    angle: f32,
) -> FloatDescriptor64 {
    let (sin, cos) = angle.sin_cos();
    let half = (scale.round() as usize).max(1);
    let weights = &*WEIGHTS;
    let mut d = [0.0f32; 64];
    for l in 0..20usize {
        let v = sample_unit(l) * scale;
        for k in 0..20usize {
            let u = sample_unit(k) * scale;
            let px = x + u * cos - v * sin;
            let py = y + u * sin + v * cos;
            let (dx, dy) = haar(integral, nearest_corner(px), nearest_corner(py), half);
            let weight = weights[l * 20 + k];
            let du = weight * (dx * cos + dy * sin);
            let dv = weight * (-dx * sin + dy * cos);
            let cell = 4 * ((l / 5) * 4 + k / 5);
            d[cell] += du;
            d[cell + 1] += du.abs();
            d[cell + 2] += dv;
            d[cell + 3] += dv.abs();
        }
    }
    let norm = d.iter().map(|v| v * v).sum::<f32>().sqrt();
    if norm > 0.0 {
        for v in &mut d {
            *v /= norm;
        }
    }
    FloatDescriptor64(d)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::{Descriptor, GrayView};
    use crate::surf::test_images::texture;

    #[test]
    fn descriptor_has_unit_norm_and_flat_patch_is_zero() {
        let (w, h) = (96, 96);
        let img = texture(w, h, 11);
        let ii = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &img,
        });
        for (x, y, s, a) in [(48.0, 48.0, 2.0, 0.3), (10.0, 80.0, 3.1, -2.0)] {
            let d = describe(&ii, x, y, s, a);
            let n = d.0.iter().map(|v| v * v).sum::<f32>().sqrt();
            assert!((n - 1.0).abs() < 1e-4, "norm {n}");
        }
        let flat = vec![9u8; w * h];
        let ii = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &flat,
        });
        assert_eq!(describe(&ii, 48.0, 48.0, 2.0, 1.0).0, [0.0; 64]);
    }

    #[test]
    fn descriptor_is_invariant_to_contrast_and_brightness() {
        let (w, h) = (80, 80);
        let img = texture(w, h, 5);
        let scaled: Vec<u8> = img.iter().map(|&p| (p / 2).saturating_add(40)).collect();
        let a = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &img,
        });
        let b = IntegralImage::new(GrayView {
            width: w,
            height: h,
            data: &scaled,
        });
        let da = describe(&a, 40.0, 40.0, 2.4, 0.7);
        let db = describe(&b, 40.0, 40.0, 2.4, 0.7);
        // Only the rounding of p / 2 separates them.
        assert!(da.distance(&db) < 0.05, "{}", da.distance(&db));
    }
}
