//! Dominant orientation from Haar wavelet responses (SURF, Bay et al. 2008, §4.1).
//!
//! Around a keypoint at `(x, y)` with scale `s`, Haar wavelets of side `4s` are evaluated
//! on the sample points `(x + i·s, y + j·s)` with `i² + j² < 36` (a disc of radius `6s`,
//! 109 points). Each response `(dx, dy)` is weighted by a Gaussian of `σ = 2s` centred on
//! the keypoint,
//!
//! ```text
//! w(i, j) = exp(−(i² + j²) / (2 · 2²)),
//! ```
//!
//! and seen as a point in the `(dx, dy)` plane. A window of angular width `π/3` slides
//! around the origin; the responses inside it are summed, and the orientation is the
//! direction of the longest sum vector:
//!
//! ```text
//! θ = atan2(Σ dy, Σ dx)   over the window maximising (Σ dx)² + (Σ dy)².
//! ```
//!
//! The window is slid exactly: it is anchored on each response angle in turn (the
//! optimum always starts at one), with a two-pointer sweep over the sorted angles.
//! Angles are measured from `+x` towards `+y` (image axes, `y` down).

use std::f32::consts::{PI, TAU};
use std::sync::LazyLock;

use super::integral::{IntegralImage, haar, nearest_corner};

/// Number of sample points with `i² + j² < 36`.
const SAMPLES: usize = 109;

/// Width of the sliding window, radians.
const WINDOW: f32 = PI / 3.0;

/// The sample offsets `(i, j)` with `i² + j² < 36` and their weights
/// `exp(−(i² + j²) / 8)`; computed once.
static SAMPLE_GRID: LazyLock<[(i32, i32, f32); SAMPLES]> = LazyLock::new(|| {
    let mut grid = [(0, 0, 0.0f32); SAMPLES];
    let mut n = 0;
    for j in -6i32..=6 {
        for i in -6i32..=6 {
            let r2 = i * i + j * j;
            if r2 < 36 && n < SAMPLES {
                grid[n] = (i, j, (-(r2 as f32) / 8.0).exp());
                n += 1;
            }
        }
    }
    grid
});

/// Dominant orientation, radians in `(−π, π]`, of the keypoint at `(x, y)` with scale
/// `scale`; 0 when there is no gradient at all.
#[must_use]
pub(crate) fn orientation(integral: &IntegralImage, x: f32, y: f32, scale: f32) -> f32 {
    // (angle, dx, dy) of each non-zero response.
    let mut responses = [(0.0f32, 0.0f32, 0.0f32); SAMPLES];
    let mut n = 0;
    let half = ((2.0 * scale).round() as usize).max(1);
    for &(i, j, weight) in SAMPLE_GRID.iter() {
        let cx = nearest_corner(x + i as f32 * scale);
        let cy = nearest_corner(y + j as f32 * scale);
        let (dx, dy) = haar(integral, cx, cy, half);
        let (dx, dy) = (dx * weight, dy * weight);
        if dx != 0.0 || dy != 0.0 {
            responses[n] = (dy.atan2(dx), dx, dy);
            n += 1;
        }
    }
    let responses = &mut responses[..n];
    if responses.is_empty() {
        return 0.0;
    }
    responses.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));

    // Window [a_start, a_start + π/3); `end` counts responses taken so far, modulo n.
    let angle_at = |k: usize| -> f32 {
        let wraps = (k / n) as f32;
        responses[k % n].0 + wraps * TAU
    };
    let (mut sum_x, mut sum_y) = (0.0f32, 0.0f32);
    let mut end = 0usize;
    let mut best = (f32::MIN, 0.0f32, 0.0f32);
    for start in 0..n {
        if end < start {
            end = start;
            (sum_x, sum_y) = (0.0, 0.0);
        }
        let limit = responses[start].0 + WINDOW;
        while end < start + n && angle_at(end) < limit {
            let (_, dx, dy) = responses[end % n];
            sum_x += dx;
            sum_y += dy;
            end += 1;
        }
        let norm2 = sum_x * sum_x + sum_y * sum_y;
        if norm2 > best.0 {
            best = (norm2, sum_x, sum_y);
        }
        let (_, dx, dy) = responses[start];
        sum_x -= dx;
        sum_y -= dy;
    }
    best.2.atan2(best.1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::GrayView;

    fn angle_diff(a: f32, b: f32) -> f32 {
        let d = (a - b).rem_euclid(TAU);
        d.min(TAU - d)
    }

    #[test]
    fn gradient_ramp_gives_its_direction() {
        let n = 101;
        for deg in [0.0f32, 30.0, 90.0, 135.0, -60.0, 180.0, -170.0] {
            let phi = deg.to_radians();
            let (c, s) = (phi.cos(), phi.sin());
            let img: Vec<u8> = (0..n * n)
                .map(|k| {
                    let (x, y) = ((k % n) as f32 - 50.0, (k / n) as f32 - 50.0);
                    (128.0 + 2.0 * (x * c + y * s)).clamp(0.0, 255.0) as u8
                })
                .collect();
            let ii = IntegralImage::new(GrayView {
                width: n,
                height: n,
                data: &img,
            });
            for scale in [1.6f32, 2.0, 3.3] {
                let theta = orientation(&ii, 50.0, 50.0, scale);
                assert!(
                    angle_diff(theta, phi) < 3f32.to_radians(),
                    "phi {deg}°, scale {scale}: got {}°",
                    theta.to_degrees()
                );
            }
        }
    }

    #[test]
    fn flat_image_has_orientation_zero() {
        let img = vec![77u8; 40 * 40];
        let ii = IntegralImage::new(GrayView {
            width: 40,
            height: 40,
            data: &img,
        });
        assert_eq!(orientation(&ii, 20.0, 20.0, 2.0), 0.0);
    }

    #[test]
    fn sample_count_is_109() {
        assert!(SAMPLE_GRID.iter().all(|&(i, j, _)| i * i + j * j < 36));
        assert_eq!(SAMPLE_GRID[SAMPLES - 1], (3, 5, (-34.0f32 / 8.0).exp()));
        let count = (-6i32..=6)
            .flat_map(|j| (-6i32..=6).map(move |i| i * i + j * j))
            .filter(|&r2| r2 < 36)
            .count();
        assert_eq!(count, SAMPLES);
    }
}
