//! The scale of the data and of its noise, for the automatic threshold: both are
//! equivariant, so scaling every coordinate by `k` scales them by `k`.

use nalgebra::Point3;

/// Robust size of a point set, in its unit: the median distance of the points from
/// their coordinate-wise median. Half the points can be anywhere (a point at 1e10 m
/// does not move it); 0 when more than half coincide.
pub(super) fn scene_scale(points: &[Point3<f64>]) -> f64 {
    if points.is_empty() {
        return 0.0;
    }
    let mut column: Vec<f64> = Vec::with_capacity(points.len());
    let centre = median_centre(points, &mut column);
    column.clear();
    column.extend(points.iter().map(|p| (p - centre).norm()));
    median(&mut column)
}

/// The coordinate-wise median of `points`, with `column` as the scratch space.
fn median_centre(points: &[Point3<f64>], column: &mut Vec<f64>) -> Point3<f64> {
    let mut centre = [0.0; 3];
    for (k, c) in centre.iter_mut().enumerate() {
        column.clear();
        column.extend(points.iter().map(|p| p[k]));
        *c = median(column);
    }
    Point3::from(centre)
}

/// Points farther than this many scene scales from the centre are left out of the
/// degeneracy test of [`check_core`].
const CORE_RADIUS: f64 = 20.0;

/// Fails when the core of the set (the points within [`CORE_RADIUS`] scene scales of
/// its median) is coincident or collinear: a few wild points (a stereo point at
/// near-zero disparity, 1e10 m away) neither make a good set degenerate nor hide a
/// degenerate one. Returns the scene scale.
pub(super) fn check_core(
    points: &[Point3<f64>],
    set: &'static str,
) -> Result<f64, crate::error::PoseError> {
    let scale = scene_scale(points);
    let coincident = crate::error::PoseError::Degenerate {
        set,
        kind: crate::error::DegeneracyKind::Coincident,
    };
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(coincident);
    }
    let mut column: Vec<f64> = Vec::with_capacity(points.len());
    let centre = median_centre(points, &mut column);
    let core = points
        .iter()
        .filter(|p| (*p - centre).norm() <= CORE_RADIUS * scale);
    crate::geometry::check_spread(core, set)?;
    Ok(scale)
}

/// The median of `v` (upper median for even lengths); 0 when empty. Reorders `v`.
pub(super) fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return 0.0;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, f64::total_cmp).1
}

/// `P(|x| < r)` for a 3D isotropic Gaussian of unit σ per axis (the χ distribution with
/// 3 degrees of freedom).
fn chi3_cdf(r: f64) -> f64 {
    libm::erf(r / std::f64::consts::SQRT_2)
        - (2.0 / std::f64::consts::PI).sqrt() * r * (-0.5 * r * r).exp()
}

/// Bisection steps (the intervals shrink to about 1e-8 of their start).
const BISECTIONS: usize = 26;

/// Median of `|x|` for a unit 3D Gaussian truncated to `|x| < x_max`.
fn truncated_median(x_max: f64) -> f64 {
    let half = 0.5 * chi3_cdf(x_max);
    let (mut lo, mut hi) = (0.0, x_max);
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        if chi3_cdf(mid) < half {
            lo = mid;
        } else {
            hi = mid;
        }
    }
    0.5 * (lo + hi)
}

/// Smallest and largest `δ/σ` the inversion considers: below, the residuals within δ
/// look uniform in the ball (σ is not identified), above, the Gaussian is not truncated.
const RATIO_RANGE: (f64, f64) = (0.25, 20.0);

/// Levels of the bisection of [`truncated_sigma`] whose `δ/σ` ratios are computed once
/// ([`Bisection`]): the midpoints of its first levels are the same in every call.
const CACHED_LEVELS: usize = 8;

/// [`truncated_sigma`]'s constants, computed once (issue 34: each is 27 evaluations of
/// [`chi3_cdf`], the same operations as when they were computed on every call, so the
/// same bits): `ratio(x) = truncated_median(x) / x` at both ends of [`RATIO_RANGE`],
/// `truncated_median` at its upper end, and `ratio` at the midpoints of the bisection's
/// first [`CACHED_LEVELS`] levels (heap order: node `k`'s halves are `2k` and `2k + 1`,
/// the root is 1).
struct Bisection {
    of_lo: f64,
    of_hi: f64,
    median_hi: f64,
    of_mid: [f64; 1 << CACHED_LEVELS],
}

/// `truncated_median(x) / x`, the ratio [`truncated_sigma`] inverts.
fn ratio_of(x: f64) -> f64 {
    truncated_median(x) / x
}

impl Bisection {
    fn new() -> Self {
        let mut of_mid = [0.0; 1 << CACHED_LEVELS];
        fill(&mut of_mid, 1, RATIO_RANGE);
        Self {
            of_lo: ratio_of(RATIO_RANGE.0),
            of_hi: ratio_of(RATIO_RANGE.1),
            median_hi: truncated_median(RATIO_RANGE.1),
            of_mid,
        }
    }

    fn get() -> &'static Self {
        static ONCE: std::sync::OnceLock<Bisection> = std::sync::OnceLock::new();
        ONCE.get_or_init(Self::new)
    }
}

/// [`Bisection::of_mid`] from node `k` (the interval `(lo, hi)`) down.
fn fill(of_mid: &mut [f64], k: usize, (lo, hi): (f64, f64)) {
    if k >= of_mid.len() {
        return;
    }
    let mid = 0.5 * (lo + hi);
    of_mid[k] = ratio_of(mid);
    fill(of_mid, 2 * k, (mid, hi));
    fill(of_mid, 2 * k + 1, (lo, mid));
}

/// The noise σ per axis (3D Gaussian) whose residuals, kept only below `delta`, have
/// median `median_within`: the inlier band truncates the noise, so the plain median
/// underestimates σ when δ is tight. `None` when the residuals look uniform within the
/// band (σ is then larger than δ / 0.25 can tell).
pub(super) fn truncated_sigma(median_within: f64, delta: f64) -> Option<f64> {
    if !(delta > 0.0 && median_within >= 0.0) {
        return None;
    }
    let ratio = median_within / delta;
    // ratio(x) = truncated_median(x) / x decreases with x = δ/σ.
    let cached = Bisection::get();
    if ratio >= cached.of_lo {
        return None;
    }
    let (mut lo, mut hi) = RATIO_RANGE;
    if ratio <= cached.of_hi {
        // Hardly truncated: the plain median of a 3D Gaussian's norm.
        return Some(median_within / cached.median_hi);
    }
    // Node k of the cached levels: the larger half (lo moves up) is 2k, the smaller 2k + 1.
    // Past the cached levels, k stays at the table's length (no entry).
    let mut k = 1;
    for _ in 0..BISECTIONS {
        let mid = 0.5 * (lo + hi);
        let of_mid = cached
            .of_mid
            .get(k)
            .copied()
            .unwrap_or_else(|| ratio_of(mid));
        let smaller = if of_mid > ratio {
            lo = mid;
            0
        } else {
            hi = mid;
            1
        };
        k = (2 * k + smaller).min(cached.of_mid.len());
    }
    Some(delta / (0.5 * (lo + hi)))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_is_robust_and_equivariant() {
        let pts: Vec<Point3<f64>> = (0..59)
            .map(|k| Point3::new(f64::from(k % 7), f64::from(k % 5), f64::from(k % 3)))
            .chain(std::iter::once(Point3::new(1e10, 0.0, 0.0)))
            .collect();
        let s = scene_scale(&pts);
        assert!(s > 1.0 && s < 5.0, "{s}");
        let mm: Vec<Point3<f64>> = pts.iter().map(|p| p * 1000.0).collect();
        assert!((scene_scale(&mm) / s - 1000.0).abs() < 1e-9);
    }

    /// [`truncated_sigma`] as it was before its constants were cached (issue 34).
    fn truncated_sigma_before(median_within: f64, delta: f64) -> Option<f64> {
        if !(delta > 0.0 && median_within >= 0.0) {
            return None;
        }
        let ratio = median_within / delta;
        let of = |x: f64| truncated_median(x) / x;
        if ratio >= of(RATIO_RANGE.0) {
            return None;
        }
        let (mut lo, mut hi) = RATIO_RANGE;
        if ratio <= of(hi) {
            return Some(median_within / truncated_median(hi));
        }
        for _ in 0..BISECTIONS {
            let mid = 0.5 * (lo + hi);
            if of(mid) > ratio {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        Some(delta / (0.5 * (lo + hi)))
    }

    #[test]
    fn cached_bisection_is_bit_identical() {
        use rand::RngExt;
        let mut rng = crate::rng::seeded(38);
        let special = [0.0, -0.0, f64::NAN, f64::INFINITY, -1.0, 1e-300, 1.0];
        let mut cases: Vec<(f64, f64)> = special
            .iter()
            .flat_map(|&a| special.iter().map(move |&b| (a, b)))
            .collect();
        // Ratios across the whole range, and exactly at the cached midpoints' values.
        cases.extend((0..3000).map(|_| (rng.random_range(0.0..1.0), 1.0)));
        cases.extend((0..300).map(|_| (rng.random_range(0.0..10.0), rng.random_range(0.1..10.0))));
        let cached = Bisection::get();
        cases.extend(cached.of_mid.iter().skip(1).map(|&r| (r, 1.0)));
        cases.extend([(cached.of_lo, 1.0), (cached.of_hi, 1.0)]);
        for (m, d) in cases {
            let got = truncated_sigma(m, d).map(f64::to_bits);
            let want = truncated_sigma_before(m, d).map(f64::to_bits);
            assert_eq!(got, want, "{m} {d}");
        }
    }

    #[test]
    fn truncation_is_undone() {
        assert!((chi3_cdf(1.538) - 0.5).abs() < 1e-3);
        // Untruncated: the median is 1.538 σ.
        let s = truncated_sigma(1.538 * 0.1, 100.0).expect("identified");
        assert!((s / 0.1 - 1.0).abs() < 1e-3, "{s}");
        // Truncated at 1.5 σ (σ = 1): the median of the kept part.
        let m = truncated_median(1.5);
        let s = truncated_sigma(m, 1.5).expect("identified");
        assert!((s - 1.0).abs() < 1e-5, "{s}");
        // Uniform in the ball: median at 0.794 δ, σ not identified.
        assert!(truncated_sigma(0.8, 1.0).is_none());
    }
}
