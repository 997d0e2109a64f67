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

use std::marker::PhantomData;

use nalgebra::{Isometry3, Matrix3, Point3};
use rand::RngExt;

use super::graph::PairGraph;
use super::{Found, PsoEstimator};
use crate::error::PoseError;
use crate::estimators::consensus::Tolerance;
use crate::estimators::mahalanobis::{inverse3, refine_mahalanobis};
use crate::geometry::{Correspondences, CovariancePair, MIN_CORRESPONDENCES};
use crate::rng::SeededRng;
use crate::simd;

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
    /// The closures as a [`PairTest`].
    struct Closures<F, G, R>(F, G, PhantomData<fn() -> R>);
    impl<R, F: Fn(usize) -> R, G: Fn(&R, usize) -> bool> PairTest for Closures<F, G, R> {
        type Row = R;
        #[inline(always)]
        fn row(&self, i: usize) -> R {
            (self.0)(i)
        }
        #[inline(always)]
        fn passes(&self, row: &R, j: usize) -> bool {
            (self.1)(row, j)
        }
    }
    chance_rate_of(n, rng, &Closures(row, passes, PhantomData))
}

/// An inlier test of a source row against a destination row, for [`chance_rate_of`].
trait PairTest {
    /// What the test prepares once per source row.
    type Row;
    /// Source row `i`, prepared.
    fn row(&self, i: usize) -> Self::Row;
    /// Whether the prepared source row passes against destination row `j`.
    fn passes(&self, row: &Self::Row, j: usize) -> bool;
}

/// [`chance_rate`] of `test`: inlined into its callers, so that a [`simd::Kernel`] compiles
/// the test into each of its instruction sets (closures would be compiled apart, once).
#[inline(always)]
fn chance_rate_of<T: PairTest>(n: usize, rng: &mut SeededRng, test: &T) -> f64 {
    if n < 2 {
        return 1.0;
    }
    let (mut hits, mut trials) = (0u64, 0u64);
    for a in 0..ROWS.min(n) {
        let i = if n <= ROWS { a } else { rng.random_range(0..n) };
        let prepared = test.row(i);
        for _ in 0..PARTNERS.min(n - 1) {
            let mut j = rng.random_range(0..n - 1);
            if j >= i {
                j += 1;
            }
            hits += u64::from(test.passes(&prepared, j));
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
    check_rate(n, support, p, triangles)
}

/// [`check_chance`] once the chance rate `p` is known.
fn check_rate(n: usize, support: usize, p: f64, triangles: f64) -> Result<(), PoseError> {
    let needed = needed_support(n, p, triangles);
    if support < needed {
        return Err(PoseError::InsufficientSupport { support, needed });
    }
    Ok(())
}

/// [`chance_rate`] of the Mahalanobis test at `pose` (gate `gate`, χ²(3) units): source row
/// `i` moved by `pose` against destination row `j`, with covariance `R Σ_s,i Rᵀ + Σ_d,j`. A
/// [`simd::Kernel`], compiled for the best instruction set of the CPU (the same operations
/// and the same draws, so the same rate; issue 34).
struct MahalanobisChance<'a> {
    data: &'a Correspondences,
    covariance: CovariancePair<'a>,
    pose: Isometry3<f64>,
    gate: f64,
    rng: &'a mut SeededRng,
}

impl simd::Kernel for MahalanobisChance<'_> {
    type Output = f64;

    #[inline(always)]
    fn run(self) -> f64 {
        let Self {
            data,
            covariance: (src_cov, dst_cov),
            pose,
            gate,
            rng,
        } = self;
        let test = MahalanobisTest {
            src: data.src(),
            dst: data.dst(),
            src_cov,
            dst_cov,
            pose,
            rotation: pose.rotation.to_rotation_matrix().into_inner(),
            gate,
        };
        chance_rate_of(data.len(), rng, &test)
    }
}

/// The test of [`MahalanobisChance`], with the rotation's matrix.
struct MahalanobisTest<'a> {
    src: &'a [Point3<f64>],
    dst: &'a [Point3<f64>],
    src_cov: &'a [Matrix3<f64>],
    dst_cov: &'a [Matrix3<f64>],
    pose: Isometry3<f64>,
    rotation: Matrix3<f64>,
    gate: f64,
}

impl PairTest for MahalanobisTest<'_> {
    /// The moved source point and its rotated covariance `R Σ_s Rᵀ`.
    type Row = (Point3<f64>, Matrix3<f64>);

    #[inline(always)]
    fn row(&self, i: usize) -> Self::Row {
        let r = &self.rotation;
        (self.pose * self.src[i], r * self.src_cov[i] * r.transpose())
    }

    #[inline(always)]
    fn passes(&self, (q, c): &Self::Row, j: usize) -> bool {
        let e = self.dst[j] - q;
        let cov = c + self.dst_cov[j];
        // eᵀ Σ⁻¹ e ≥ |e|² / tr Σ: most pairs fail without an inversion.
        e.norm_squared() < self.gate * cov.trace()
            && inverse3(&cov).is_some_and(|w| e.dot(&(w * e)) < self.gate)
    }
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
        let p = simd::dispatch(MahalanobisChance {
            data,
            covariance: (src_cov, dst_cov),
            pose: found.pose,
            gate,
            rng,
        });
        check_rate(data.len(), found.inliers.len(), p, triangles)
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

    /// The Mahalanobis chance rate through the kernel, dispatched and baseline, against the
    /// closures `checked` passed to `check_chance` before it (issue 34): the same rate, and
    /// the generator left in the same state.
    #[test]
    fn mahalanobis_chance_matches_the_closures_in_every_instruction_set() {
        use nalgebra::Vector3;
        let mut rng = crate::rng::seeded(42);
        let value = |rng: &mut SeededRng| -> f64 {
            match rng.random_range(0..60) {
                0 => 0.0,
                1 => -0.0,
                2 => f64::NAN,
                3 => f64::INFINITY,
                _ => rng.random_range(-0.5..0.5),
            }
        };
        let mut rates = Vec::new();
        for case in 0..30 {
            let n = [50, 128, 300][case % 3];
            let (src, dst) =
                crate::estimators::test_scenes::random_clouds(&mut rng, n, -2.0..2.0, -2.0..2.0);
            let cov = |rng: &mut SeededRng| {
                let a = Matrix3::from_fn(|_, _| value(rng));
                a * a.transpose()
            };
            let sc: Vec<Matrix3<f64>> = (0..n).map(|_| cov(&mut rng)).collect();
            let dc: Vec<Matrix3<f64>> = (0..n).map(|_| cov(&mut rng)).collect();
            let data = Correspondences::new(src.clone(), dst.clone()).expect("valid");
            let pose = Isometry3::new(
                Vector3::new(rng.random_range(-0.5..0.5), 0.0, 0.1),
                Vector3::new(0.0, rng.random_range(-0.3..0.3), 0.01),
            );
            let gate = 11.345;
            let seed: u64 = rng.random();
            // The reference: the closures as `checked` passed them.
            let r = pose.rotation.to_rotation_matrix().into_inner();
            let mut reference_rng = crate::rng::seeded(seed);
            let expected = chance_rate(
                n,
                &mut reference_rng,
                |i| (pose * src[i], r * sc[i] * r.transpose()),
                |(q, c), j| {
                    let e = dst[j] - q;
                    let cov = c + dc[j];
                    e.norm_squared() < gate * cov.trace()
                        && inverse3(&cov).is_some_and(|w| e.dot(&(w * e)) < gate)
                },
            );
            let after: u64 = reference_rng.random();
            let run = || {
                let mut rng = crate::rng::seeded(seed);
                let p = simd::dispatch(MahalanobisChance {
                    data: &data,
                    covariance: (&sc, &dc),
                    pose,
                    gate,
                    rng: &mut rng,
                });
                (p.to_bits(), rng.random::<u64>())
            };
            assert_eq!(run(), (expected.to_bits(), after), "case {case}");
            assert_eq!(
                simd::baseline(run),
                (expected.to_bits(), after),
                "case {case}"
            );
            rates.push(expected);
        }
        // Neither no hit nor all: the test compares rates that depend on the data.
        assert!(rates.iter().any(|&p| p > 0.05) && rates.iter().any(|&p| p < 0.95));
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
