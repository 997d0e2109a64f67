//! The self-check: is the winning consensus more than what wrong matches agree on by
//! chance at this threshold?
//!
//! Under the pose `T` found, a wrong match `(s_i, d_j)` (the destination of some other
//! point) passes the inlier test with some probability `p`. `p` is measured on the data
//! itself: `T s_i` is tested against destinations `d_j, j ≠ i` of random other rows, so
//! it holds for wrong matches that land on real scene structure, not only uniform ones.
//! A search that tries many motions can find one agreeing with 3 matches by
//! construction (a rigid triangle) plus chance agreements: the number of chance
//! agreements is Poisson with mean `λ = n p`, and a search over `H` triangles can reach
//! its upper tail. `H` is the number of triangles whose three pairs keep their lengths
//! (only those define a motion three matches agree with), counted in the consistency
//! graph and scaled from its sample to all `n` rows, at most `C(n, 3)`. The consensus is
//! accepted when `k - 3` agreements have Poisson tail probability below `α / H`
//! (Bonferroni over the triangles, `α` = [`FALSE_ALARM`]): a consensus that chance could
//! have produced is [`PoseError::InsufficientSupport`] with the support needed, never a
//! plain success.

use rand::RngExt;

use super::graph::PairGraph;
use super::{Found, PsoEstimator};
use crate::error::PoseError;
use crate::estimators::consensus::Tolerance;
use crate::estimators::mahalanobis::{inverse3, refine_mahalanobis};
use crate::geometry::{Correspondences, MIN_CORRESPONDENCES};
use crate::rng::SeededRng;

/// Probability that a consensus of wrong matches passes, over all triangles.
pub(super) const FALSE_ALARM: f64 = 0.01;

/// Source rows sampled to measure the chance agreement rate.
const ROWS: usize = 128;
/// Destination rows each sampled source row is tested against.
const PARTNERS: usize = 128;

/// The least support a consensus among `n` correspondences needs when a wrong match
/// passes its test with probability `p` and the search could start from `triangles`
/// rigid triples (at most `C(n, 3)` count).
pub(super) fn needed_support(n: usize, p: f64, triangles: f64) -> usize {
    let lambda = n as f64 * p.clamp(0.0, 1.0);
    let ln_h = triangles.max(1.0).ln().min(ln_choose(n as f64, 3.0));
    let limit = FALSE_ALARM.ln() - ln_h;
    // ln P(X >= j) for X ~ Poisson(λ), j = 0, 1, ...: sum the terms from j upwards
    // (they fall fast beyond λ), in log space.
    let mut j = 0usize;
    loop {
        if ln_poisson_tail(lambda, j) < limit || j >= n {
            return (j + 3).max(MIN_CORRESPONDENCES);
        }
        j += 1;
    }
}

/// `ln C(n, k)` by the log-gamma function.
fn ln_choose(n: f64, k: f64) -> f64 {
    if n < k {
        return 0.0;
    }
    libm::lgamma(n + 1.0) - libm::lgamma(k + 1.0) - libm::lgamma(n - k + 1.0)
}

/// `ln P(X >= j)` for `X ~ Poisson(λ)`.
fn ln_poisson_tail(lambda: f64, j: usize) -> f64 {
    if j == 0 {
        return 0.0;
    }
    if lambda <= 0.0 {
        return f64::NEG_INFINITY;
    }
    let ln_term = |m: f64| -lambda + m * lambda.ln() - libm::lgamma(m + 1.0);
    let first = ln_term(j as f64);
    // Sum terms relative to the first until they stop mattering.
    let (mut sum, mut ratio, mut m) = (1.0, 1.0, j as f64);
    for _ in 0..10_000 {
        m += 1.0;
        ratio *= lambda / m;
        sum += ratio;
        if ratio < 1e-12 * sum {
            break;
        }
    }
    // Below the mean the tail is close to 1: never above it.
    (first + sum.ln()).min(0.0)
}

/// The rate at which wrong matches pass `passes(&row(i), j)` (source row `i`, prepared
/// once by `row`, against destination row `j`), measured on random pairs of different
/// rows; a Bayesian estimate `(hits + 1) / (trials + 2)` so that no hit does not mean
/// "impossible".
pub(super) fn chance_rate<R>(
    n: usize,
    rng: &mut SeededRng,
    row: impl Fn(usize) -> R,
    passes: impl Fn(&R, usize) -> bool,
) -> f64 {
    if n < 2 {
        return 1.0;
    }
    let (mut hits, mut trials) = (0u64, 0u64);
    for a in 0..ROWS.min(n) {
        let i = if n <= ROWS { a } else { rng.random_range(0..n) };
        let prepared = row(i);
        for _ in 0..PARTNERS.min(n - 1) {
            let mut j = rng.random_range(0..n - 1);
            if j >= i {
                j += 1;
            }
            hits += u64::from(passes(&prepared, j));
            trials += 1;
        }
    }
    (hits as f64 + 1.0) / (trials as f64 + 2.0)
}

/// Fails with [`PoseError::InsufficientSupport`] when `support` agreements could be
/// chance (see the module documentation); `passes(&row(i), j)` is the inlier test of
/// source row `i` against destination row `j` at the pose found.
pub(super) fn check_chance<R>(
    n: usize,
    support: usize,
    triangles: f64,
    rng: &mut SeededRng,
    row: impl Fn(usize) -> R,
    passes: impl Fn(&R, usize) -> bool,
) -> Result<(), PoseError> {
    let p = chance_rate(n, rng, row, passes);
    let needed = needed_support(n, p, triangles);
    if support < needed {
        return Err(PoseError::InsufficientSupport { support, needed });
    }
    Ok(())
}

impl PsoEstimator {
    /// The self-check on `found`; with covariances, after the Mahalanobis refinement
    /// (step 6, which then counts far points by their precise lateral position) and on
    /// its test.
    pub(super) fn checked(
        &self,
        data: &Correspondences,
        found: &mut Found,
        graph: &PairGraph,
        tol: Tolerance<'_>,
        rng: &mut SeededRng,
    ) -> Result<(), PoseError> {
        let triangles = triangles(data.len(), graph);
        let Some((src_cov, dst_cov)) = data.noise_covariance() else {
            return self.check(data, found, tol, triangles, rng);
        };
        let gate = self.config.sigma_multiplier.powi(2);
        if let Ok((pose, inliers)) =
            refine_mahalanobis(data, &found.pose, gate, self.config.refine_rounds.max(3))
        {
            found.pose = pose;
            found.inliers = inliers;
        }
        let (src, dst, pose) = (data.src(), data.dst(), found.pose);
        let r = pose.rotation.to_rotation_matrix().into_inner();
        check_chance(
            data.len(),
            found.inliers.len(),
            triangles,
            rng,
            |i| (pose * src[i], r * src_cov[i] * r.transpose()),
            |(q, c), j| {
                let e = dst[j] - q;
                let cov = c + dst_cov[j];
                // eᵀ Σ⁻¹ e ≥ |e|² / tr Σ: most pairs fail without an inversion.
                e.norm_squared() < gate * cov.trace()
                    && inverse3(&cov).is_some_and(|w| e.dot(&(w * e)) < gate)
            },
        )
    }

    /// The self-check of [`check`] on the isotropic test at `tol`.
    pub(super) fn check(
        &self,
        data: &Correspondences,
        found: &Found,
        tol: Tolerance<'_>,
        triangles: f64,
        rng: &mut SeededRng,
    ) -> Result<(), PoseError> {
        let (src, dst, pose) = (data.src(), data.dst(), found.pose);
        check_chance(
            data.len(),
            found.inliers.len(),
            triangles,
            rng,
            |i| (pose * src[i], tol.at(i).powi(2)),
            |(q, t2), j| (dst[j] - q).norm_squared() < *t2,
        )
    }
}

/// The rigid triples among `n` rows, estimated from those of `graph`'s sample.
pub(super) fn triangles(n: usize, graph: &PairGraph) -> f64 {
    let m = graph.points().max(1) as f64;
    graph.triangles() as f64 * (n as f64 / m).powi(3)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn more_chance_needs_more_support() {
        // 600 rows: no chance agreement still needs a few beyond the triangle.
        let all = 600.0 * 599.0 * 598.0 / 6.0;
        let low = needed_support(600, 1e-6, all);
        let mid = needed_support(600, 1e-3, all);
        let high = needed_support(600, 1e-2, all);
        assert!(low >= 4 && low < mid && mid < high, "{low} {mid} {high}");
        // λ = 6 expected chance agreements: the winner needs far more than 6.
        assert!(high > 15, "{high}");
        // 20 000 rows at λ = 20: a few inliers are not enough, 200 are.
        let big = needed_support(20_000, 1e-3, 1e12);
        assert!(big > 30 && big < 200, "{big}");
        // Fewer rigid triples to start from: less to fear from chance.
        assert!(needed_support(600, 1e-3, 1e4) < mid);
    }

    #[test]
    fn poisson_tail_matches_a_direct_sum() {
        let lambda: f64 = 2.5;
        let direct: f64 = (0..4)
            .map(|m| (-lambda).exp() * lambda.powi(m) / libm::tgamma(f64::from(m) + 1.0))
            .sum();
        let tail = ln_poisson_tail(lambda, 4).exp();
        assert!(
            (tail - (1.0 - direct)).abs() < 1e-9,
            "{tail} vs {}",
            1.0 - direct
        );
    }
}
