//! Whether a pair's scene can tell a disparity error from the scene's scale.
//!
//! A plane of the scene, `n · X = c`, has an inverse depth linear in the image
//! coordinates, so its disparities `d = f b / Z` lie on a plane in `(u, v, d)`. A constant
//! disparity offset, or a term linear in `x` (the causes rigidity estimates), adds a plane
//! to every disparity: the scene triangulated with the wrong calibration is again one
//! plane, at another distance and slant. Seen from two places, a plane and that other
//! plane differ only by the small change of the offset's share of the disparity between
//! the two frames (`a t / Z` pixels for a wall `Z` metres ahead approached by `t`): the
//! fit of such a term then rests on a few hundredths of a pixel, where the front end's
//! own sub-pixel biases (which change with the texture's scale as the camera moves) are
//! as large. On a rendered wall approached along the optical axis, an exact rig got an
//! offset of more than the true disparity and a path a third short (issue 29).
//!
//! So a pair adds rigidity evidence only when its matches do not lie on one plane in
//! `(u, v, d)`: the robust spread of their disparities about the best plane must exceed
//! the disparity noise by [`MIN_OFF_PLANE_SIGMAS`]. The test does not depend on the
//! calibration error it is a guard for (an offset or a linear term keeps a plane a plane),
//! on units or on the scene's size; it is in pixels of disparity against the front end's
//! disparity noise, so it does not depend on the image size either.

use nalgebra::{Matrix3, Vector3};

/// How many disparity standard deviations the matches' robust spread about their best
/// plane in `(u, v, d)` must reach for the pair's scene to count as more than one plane.
/// Two: a single plane measured with the assumed noise spreads by one (the residual's
/// robust scale), so twice that is clearly more; any real street scene (ground, fronts,
/// far objects) spreads by pixels to tens of pixels.
pub const MIN_OFF_PLANE_SIGMAS: f64 = 2.0;

/// The robust spread, pixels, of the disparities `d` of the points `(u, v, d)` (pixels)
/// about their best plane `d = α + β u + γ v`: 1.4826 times the median absolute residual
/// (the standard deviation for Gaussian residuals). The plane is fitted by least squares,
/// then again on the points within three robust spreads of it, so that a few wrong
/// disparities, even in one part of the image, do not tilt it. `None` for fewer than 4
/// points or points on one line of the image.
#[must_use]
pub fn off_plane_spread_px(points: &[(f64, f64, f64)]) -> Option<f64> {
    if points.len() < 4 {
        return None;
    }
    let n = points.len() as f64;
    let (mu, mv) = points
        .iter()
        .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
    let row = |u: f64, v: f64| Vector3::new(1.0, u - mu, v - mv);
    let fit = |within: f64, plane: Option<&Vector3<f64>>| {
        let mut a = Matrix3::<f64>::zeros();
        let mut b = Vector3::<f64>::zeros();
        for &(u, v, d) in points {
            let x = row(u, v);
            if plane.is_none_or(|p| (d - p.dot(&x)).abs() <= within) {
                a += x * x.transpose();
                b += x * d;
            }
        }
        let p = a.cholesky()?.solve(&b);
        p.iter().all(|c| c.is_finite()).then_some(p)
    };
    let first = fit(f64::INFINITY, None)?;
    // One buffer for both spreads (issue 34: it was allocated for each).
    let mut r: Vec<f64> = Vec::with_capacity(points.len());
    let mut spread = |plane: &Vector3<f64>| {
        r.clear();
        r.extend(
            points
                .iter()
                .map(|&(u, v, d)| (d - plane.dot(&row(u, v))).abs()),
        );
        let mid = r.len() / 2;
        1.4826 * *r.select_nth_unstable_by(mid, f64::total_cmp).1
    };
    let second = fit(3.0 * spread(&first), Some(&first)).unwrap_or(first);
    Some(spread(&second))
}

/// True when the points `(u, v, d)` (pixels) show more than one plane: their
/// [`off_plane_spread_px`] reaches `min_sigmas` (default [`MIN_OFF_PLANE_SIGMAS`]) times
/// the disparity noise `disparity_sigma_px`. False when the spread cannot be measured;
/// always true for `min_sigmas` of 0 or less (the check off).
#[must_use]
pub fn more_than_one_plane(
    points: &[(f64, f64, f64)],
    disparity_sigma_px: f64,
    min_sigmas: f64,
) -> bool {
    if min_sigmas.is_nan() || min_sigmas <= 0.0 {
        return true;
    }
    off_plane_spread_px(points).is_some_and(|s| s >= min_sigmas * disparity_sigma_px)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// [`off_plane_spread_px`] as it was before its spreads shared a buffer (issue 34).
    fn off_plane_spread_px_before(points: &[(f64, f64, f64)]) -> Option<f64> {
        if points.len() < 4 {
            return None;
        }
        let n = points.len() as f64;
        let (mu, mv) = points
            .iter()
            .fold((0.0, 0.0), |(a, b), p| (a + p.0 / n, b + p.1 / n));
        let row = |u: f64, v: f64| Vector3::new(1.0, u - mu, v - mv);
        let spread = |plane: &Vector3<f64>| {
            let mut r: Vec<f64> = points
                .iter()
                .map(|&(u, v, d)| (d - plane.dot(&row(u, v))).abs())
                .collect();
            let mid = r.len() / 2;
            1.4826 * *r.select_nth_unstable_by(mid, f64::total_cmp).1
        };
        let fit = |within: f64, plane: Option<&Vector3<f64>>| {
            let mut a = Matrix3::<f64>::zeros();
            let mut b = Vector3::<f64>::zeros();
            for &(u, v, d) in points {
                let x = row(u, v);
                if plane.is_none_or(|p| (d - p.dot(&x)).abs() <= within) {
                    a += x * x.transpose();
                    b += x * d;
                }
            }
            let p = a.cholesky()?.solve(&b);
            p.iter().all(|c| c.is_finite()).then_some(p)
        };
        let first = fit(f64::INFINITY, None)?;
        let second = fit(3.0 * spread(&first), Some(&first)).unwrap_or(first);
        Some(spread(&second))
    }

    #[test]
    fn shared_buffer_keeps_the_bits() {
        use rand::{RngExt, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(3803);
        for case in 0..500 {
            let n = rng.random_range(0..300);
            let pts: Vec<(f64, f64, f64)> = (0..n)
                .map(|_| {
                    let mut c = || match rng.random_range(0..40) {
                        0 => 0.0,
                        1 => -0.0,
                        2 => f64::NAN,
                        3..=8 => f64::from(rng.random_range(0..3u8)), // ties
                        _ => rng.random_range(-100.0..1300.0),
                    };
                    (c(), c(), c())
                })
                .collect();
            let bits = |s: Option<f64>| s.map(f64::to_bits);
            assert_eq!(
                bits(off_plane_spread_px(&pts)),
                bits(off_plane_spread_px_before(&pts)),
                "case {case}"
            );
        }
    }

    #[test]
    fn a_plane_is_one_plane_whatever_its_offset_and_slant() {
        // A slanted plane's disparities, with a constant and a linear-in-u error added,
        // and ±0.1 px of alternating noise: still one plane.
        let pts: Vec<_> = (0..400)
            .map(|i| {
                let (u, v) = (f64::from(i % 20) * 24.0, f64::from(i / 20) * 14.0);
                let noise = if i % 3 == 0 { 0.1 } else { -0.05 };
                (u, v, 20.0 + 0.01 * u - 0.02 * v + 1.5 + 0.003 * u + noise)
            })
            .collect();
        let s = off_plane_spread_px(&pts).expect("a spread");
        assert!(s < 0.2, "{s}");
        assert!(!more_than_one_plane(&pts, 0.25, MIN_OFF_PLANE_SIGMAS));
        // Half the points on a second plane 8 px nearer: more than one plane.
        let two: Vec<_> = pts
            .iter()
            .enumerate()
            .map(|(i, &(u, v, d))| (u, v, if i % 2 == 0 { d + 8.0 } else { d }))
            .collect();
        assert!(more_than_one_plane(&two, 0.25, MIN_OFF_PLANE_SIGMAS));
        // A few wrong disparities do not make a plane a scene.
        let mut few = pts.clone();
        for p in few.iter_mut().step_by(20) {
            p.2 += 30.0;
        }
        assert!(!more_than_one_plane(&few, 0.25, MIN_OFF_PLANE_SIGMAS));
        // Too few points, or all on one image row and column: nothing measured.
        assert_eq!(off_plane_spread_px(&pts[..3]), None);
        let line: Vec<_> = (0..10).map(|i| (f64::from(i), 5.0, 3.0)).collect();
        assert_eq!(off_plane_spread_px(&line), None);
        assert!(!more_than_one_plane(&line, 0.25, MIN_OFF_PLANE_SIGMAS));
        // The check off: every scene counts.
        assert!(more_than_one_plane(&line, 0.25, 0.0));
    }
}
