//! Length-consistent point pairs: the translation-free data the `pso` swarm scores.

use nalgebra::{Matrix3, UnitQuaternion};
use rand::RngExt;

use super::PsoEstimatorConfig;
use crate::arun::arun_pairs;
use crate::geometry::{Correspondences, particle_from_rotation};
use crate::rng::SeededRng;

/// Shortest source pair, as a multiple of δ, that is worth scoring...
const MIN_PAIR_LENGTH_FACTOR: f64 = 5.0;
/// ...unless the scene is small: then a tenth of its largest principal extent.
const MIN_PAIR_LENGTH_EXTENT: f64 = 0.1;
/// Random pair sampling stops once this many times `max_pairs` consistent pairs are found.
const ENOUGH_PAIRS_FACTOR: usize = 16;
/// Cost changes below this fraction of one pair's truncation cost `tol²` do not count.
const COST_QUANTUM: f64 = 0.01;
/// Tries per seed when looking for a consistent triangle.
const SEED_TRIES: usize = 16;

/// Consistent pairs: all of them as a graph (for minimal samples), and a bounded subset
/// laid out as structure-of-arrays for the fitness loop.
pub(super) struct PairSet {
    /// Scored pairs, source differences `a = s_i - s_j` (metres).
    a: [Vec<f64>; 3],
    /// Scored pairs, destination differences `b = d_i - d_j` (metres).
    b: [Vec<f64>; 3],
    /// Scored pairs' point indices.
    scored: Vec<(u32, u32)>,
    /// Every consistent pair found.
    all: Vec<(u32, u32)>,
    /// Adjacency of the consistency graph, compressed rows: neighbours of `i` are
    /// `neighbours[offsets[i]..offsets[i + 1]]`.
    offsets: Vec<usize>,
    neighbours: Vec<u32>,
    /// Pair tolerance `2δ`, metres.
    tol_m: f64,
    /// Number of points.
    n: usize,
}

#[inline]
fn consistent(data: &Correspondences, i: usize, j: usize, tol_m: f64, min_len_m: f64) -> bool {
    let la = (data.src()[i] - data.src()[j]).norm();
    let lb = (data.dst()[i] - data.dst()[j]).norm();
    la >= min_len_m && (la - lb).abs() < tol_m
}

impl PairSet {
    /// Finds the consistent pairs (step 1 of the estimator).
    pub(super) fn build(
        data: &Correspondences,
        cfg: &PsoEstimatorConfig,
        rng: &mut SeededRng,
    ) -> Self {
        let n = data.len();
        let tol_m = 2.0 * cfg.threshold_m;
        let extent_m = crate::geometry::spread(data.src())[0];
        let min_len_m =
            (MIN_PAIR_LENGTH_FACTOR * cfg.threshold_m).min(MIN_PAIR_LENGTH_EXTENT * extent_m);
        let total = n * (n - 1) / 2;
        let mut all = Vec::new();
        if total <= cfg.pair_budget {
            for i in 0..n {
                for j in i + 1..n {
                    if consistent(data, i, j, tol_m, min_len_m) {
                        all.push((i as u32, j as u32));
                    }
                }
            }
        } else {
            // Random pairs until the budget is spent or plenty of consistent ones are found.
            let enough = ENOUGH_PAIRS_FACTOR.saturating_mul(cfg.max_pairs);
            for _ in 0..cfg.pair_budget {
                if all.len() >= enough {
                    break;
                }
                let i = rng.random_range(0..n);
                let j = rng.random_range(0..n);
                if i != j && consistent(data, i, j, tol_m, min_len_m) {
                    all.push((i.min(j) as u32, i.max(j) as u32));
                }
            }
        }
        // Compressed adjacency.
        let mut offsets = vec![0usize; n + 1];
        for &(i, j) in &all {
            offsets[i as usize + 1] += 1;
            offsets[j as usize + 1] += 1;
        }
        for k in 0..n {
            offsets[k + 1] += offsets[k];
        }
        let mut fill = offsets.clone();
        let mut neighbours = vec![0u32; 2 * all.len()];
        for &(i, j) in &all {
            neighbours[fill[i as usize]] = j;
            fill[i as usize] += 1;
            neighbours[fill[j as usize]] = i;
            fill[j as usize] += 1;
        }
        // Bounded random subset to score (partial Fisher-Yates), kept in index order.
        let mut scored = all.clone();
        if scored.len() > cfg.max_pairs {
            for k in 0..cfg.max_pairs {
                let r = rng.random_range(k..scored.len());
                scored.swap(k, r);
            }
            scored.truncate(cfg.max_pairs);
            scored.sort_unstable();
        }
        let mut a: [Vec<f64>; 3] = Default::default();
        let mut b: [Vec<f64>; 3] = Default::default();
        for &(i, j) in &scored {
            let da = data.src()[i as usize] - data.src()[j as usize];
            let db = data.dst()[i as usize] - data.dst()[j as usize];
            for c in 0..3 {
                a[c].push(da[c]);
                b[c].push(db[c]);
            }
        }
        Self {
            a,
            b,
            scored,
            all,
            offsets,
            neighbours,
            tol_m,
            n,
        }
    }

    /// True when no pair is consistent.
    pub(super) fn is_empty(&self) -> bool {
        self.scored.is_empty()
    }

    /// The particle score of a rotation: (scored pairs not supporting it, truncated cost
    /// `Σ min(|e|², tol²)` in units of `COST_QUANTUM tol²`, rounded), compared
    /// lexicographically, lower is better. The rounding makes negligible gains ties, so the
    /// swarm's stall test can stop it.
    #[inline]
    pub(super) fn score(&self, q: &UnitQuaternion<f64>, tol_m: f64) -> (usize, f64) {
        let m: Matrix3<f64> = q.to_rotation_matrix().into_inner();
        let tol2 = tol_m * tol_m;
        let [ax, ay, az] = &self.a;
        let [bx, by, bz] = &self.b;
        let mut support = 0usize;
        let mut cost = 0.0;
        for k in 0..ax.len() {
            let ex = bx[k] - (m[(0, 0)] * ax[k] + m[(0, 1)] * ay[k] + m[(0, 2)] * az[k]);
            let ey = by[k] - (m[(1, 0)] * ax[k] + m[(1, 1)] * ay[k] + m[(1, 2)] * az[k]);
            let ez = bz[k] - (m[(2, 0)] * ax[k] + m[(2, 1)] * ay[k] + m[(2, 2)] * az[k]);
            let e2 = ex * ex + ey * ey + ez * ez;
            support += usize::from(e2 < tol2);
            cost += e2.min(tol2);
        }
        (ax.len() - support, (cost / (COST_QUANTUM * tol2)).round())
    }

    /// Up to `k` points taking part in the most scored pairs that support rotation `m`,
    /// most first (ties by index); points in no supporting pair are left out.
    pub(super) fn anchors(&self, m: &Matrix3<f64>, k: usize) -> Vec<usize> {
        let tol2 = self.tol_m * self.tol_m;
        let mut count = vec![0u32; self.n];
        let [ax, ay, az] = &self.a;
        let [bx, by, bz] = &self.b;
        for (p, &(i, j)) in self.scored.iter().enumerate() {
            let a = nalgebra::Vector3::new(ax[p], ay[p], az[p]);
            let b = nalgebra::Vector3::new(bx[p], by[p], bz[p]);
            if (b - m * a).norm_squared() < tol2 {
                count[i as usize] += 1;
                count[j as usize] += 1;
            }
        }
        let mut order: Vec<usize> = (0..self.n).filter(|&i| count[i] > 0).collect();
        order.sort_by(|&x, &y| count[y].cmp(&count[x]).then(x.cmp(&y)));
        order.truncate(k);
        order
    }

    /// Rotation vectors solved from up to `count` consistent triangles `(i, j, m)` (all
    /// three pairs length-consistent), for seeding particles.
    pub(super) fn minimal_sample_seeds(
        &self,
        data: &Correspondences,
        count: usize,
        rng: &mut SeededRng,
    ) -> Vec<[f64; 3]> {
        let mut seeds = Vec::with_capacity(count);
        if self.all.is_empty() {
            return seeds;
        }
        let (src, dst) = (data.src(), data.dst());
        for _ in 0..count {
            for _ in 0..SEED_TRIES {
                let (i, j) = self.all[rng.random_range(0..self.all.len())];
                let (i, j) = (i as usize, j as usize);
                let row = &self.neighbours[self.offsets[i]..self.offsets[i + 1]];
                let m = row[rng.random_range(0..row.len())] as usize;
                if m == j || !consistent(data, j, m, self.tol_m, 0.0) {
                    continue;
                }
                let tri = [i, j, m];
                if let Ok(pose) = arun_pairs(tri.iter().map(|&k| (&src[k], &dst[k], 1.0))) {
                    seeds.push(particle_from_rotation(&pose.rotation));
                    break;
                }
            }
        }
        seeds
    }
}
