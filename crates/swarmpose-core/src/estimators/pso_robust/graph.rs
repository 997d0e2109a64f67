//! The consistency graph of the hypothesis points: length-consistent pairs, their
//! common-neighbour counts, and the scored pairs in structure-of-arrays layout.
//!
//! A rigid motion keeps distances, so two correct matches `i, j` satisfy
//! `| |d_i - d_j| - |s_i - s_j| | < δ_i + δ_j`. Correct matches form a dense cluster of
//! this graph: a pair of them shares every other correct match as a common neighbour,
//! while a pair involving a wrong match shares few. Pairs are ranked by that count, so the
//! scored pairs are mostly correct even when most matches are wrong.

use nalgebra::{Matrix3, UnitQuaternion, Vector3};
use rand::RngExt;

use crate::arun::arun_pairs;
use crate::estimators::consensus::Tolerance;
use crate::geometry::{Correspondences, particle_from_rotation};
use crate::rng::SeededRng;
use crate::simd;

/// Cost changes below this fraction of one pair's truncation cost do not count.
const COST_QUANTUM: f64 = 0.01;
/// Lanes of the fitness loop.
const LANES: usize = 8;
/// Tries per seed when looking for a triangle.
const SEED_TRIES: usize = 8;

/// Consistent pairs of a set of hypothesis points.
pub(super) struct PairGraph {
    /// Local index -> index in the correspondences.
    points: Vec<usize>,
    /// `u64` words per adjacency row.
    words: usize,
    /// Adjacency bitsets, one row of `words` words per local point.
    rows: Vec<u64>,
    /// Every consistent pair `(i, j, common neighbours)` in local indices, `i < j`, in
    /// lexicographic order.
    pairs: Vec<(u32, u32, u32)>,
    /// The (at most `max_pairs`) best ranked pairs, in rank order: the scored pairs.
    ranked: Vec<(u32, u32, u32)>,
    /// Scored pairs: source differences `a = s_i - s_j`, metres (single precision: the
    /// fitness loop vectorises).
    a: [Vec<f32>; 3],
    /// Scored pairs: destination differences `b = d_i - d_j`, metres.
    b: [Vec<f32>; 3],
    /// Scored pairs: reciprocal squared tolerance `1 / (δ_i + δ_j)^2`, 1/m²; padding pairs
    /// (all zero) follow the real ones up to a multiple of `LANES`.
    inv_tol2: Vec<f32>,
    /// Number of padding pairs.
    padding: usize,
}

impl PairGraph {
    /// The graph of `points` (indices into `data`), keeping at most `max_pairs` for
    /// scoring; pairs shorter than `min_len_m` in the source set are left out.
    pub(super) fn build(
        data: &Correspondences,
        points: Vec<usize>,
        tol: Tolerance<'_>,
        max_pairs: usize,
        min_len_m: f64,
    ) -> Self {
        let m = points.len();
        let words = m.div_ceil(64);
        let (src, dst) = (data.src(), data.dst());
        // Single precision, structure of arrays: the inner loop vectorises. Lengths of
        // tens of metres keep ~5 µm of precision, far below any useful δ.
        let column =
            |f: &dyn Fn(usize) -> f64| points.iter().map(|&g| f(g) as f32).collect::<Vec<f32>>();
        let (sx, sy, sz) = (
            column(&|g| src[g].x),
            column(&|g| src[g].y),
            column(&|g| src[g].z),
        );
        let (dx, dy, dz) = (
            column(&|g| dst[g].x),
            column(&|g| dst[g].y),
            column(&|g| dst[g].z),
        );
        let tl = column(&|g| tol.at(g));
        let (rows, mut pairs) = simd::dispatch(Consistency {
            s: [&sx, &sy, &sz],
            d: [&dx, &dy, &dz],
            tol: &tl,
            min_len: min_len_m as f32,
        });
        count_common_dispatched(&mut pairs, &rows, words);
        let ranked = ranked_prefix(&pairs, max_pairs, m);
        let scored = ranked.len();
        let lanes = scored.next_multiple_of(LANES);
        let mut graph = Self {
            points,
            words,
            rows,
            pairs,
            ranked,
            a: std::array::from_fn(|_| Vec::with_capacity(lanes)),
            b: std::array::from_fn(|_| Vec::with_capacity(lanes)),
            inv_tol2: Vec::with_capacity(lanes),
            padding: scored.next_multiple_of(LANES) - scored,
        };
        for k in 0..scored {
            let (gi, gj) = graph.global(k);
            let (da, db) = (src[gi] - src[gj], dst[gi] - dst[gj]);
            for c in 0..3 {
                graph.a[c].push(da[c] as f32);
                graph.b[c].push(db[c] as f32);
            }
            graph
                .inv_tol2
                .push((tol.at(gi) + tol.at(gj)).powi(-2) as f32);
        }
        for _ in 0..graph.padding {
            for c in 0..3 {
                graph.a[c].push(0.0);
                graph.b[c].push(0.0);
            }
            graph.inv_tol2.push(0.0);
        }
        graph
    }

    /// Global indices of scored pair `k`.
    fn global(&self, k: usize) -> (usize, usize) {
        let (i, j, _) = self.ranked[k];
        (self.points[i as usize], self.points[j as usize])
    }

    /// Number of points in the graph.
    pub(super) fn points(&self) -> usize {
        self.points.len()
    }

    /// Number of triangles of consistent pairs (three points whose three pairs all keep
    /// their lengths): the rigid triples a search could start a motion from.
    pub(super) fn triangles(&self) -> u64 {
        self.pairs.iter().map(|p| u64::from(p.2)).sum::<u64>() / 3
    }

    /// Number of scored pairs.
    pub(super) fn scored(&self) -> usize {
        self.inv_tol2.len() - self.padding
    }

    /// Normalised residual `|b - R a|^2 / τ^2` of scored pair `k` (supports when < 1).
    #[inline]
    fn normalised_residual2(&self, m: &Matrix3<f64>, k: usize) -> f64 {
        let a = Vector3::new(self.a[0][k], self.a[1][k], self.a[2][k]).cast::<f64>();
        let b = Vector3::new(self.b[0][k], self.b[1][k], self.b[2][k]).cast::<f64>();
        (b - m * a).norm_squared() * f64::from(self.inv_tol2[k])
    }

    /// The particle score of a rotation: (scored pairs not supporting it, normalised
    /// truncated cost `Σ min(|e|²/τ², 1)` in units of `COST_QUANTUM`, rounded), compared
    /// lexicographically, lower is better. The rounding makes negligible gains ties, so the
    /// swarm's stall test can stop it.
    #[inline]
    pub(super) fn score(&self, q: &UnitQuaternion<f64>) -> (usize, f64) {
        let m: Matrix3<f32> = q.to_rotation_matrix().into_inner().cast::<f32>();
        let (support, cost) = simd::dispatch(Score { graph: self, m });
        // Padding pairs have zero residual: they "support" every rotation.
        let support = support.iter().sum::<u32>() as usize - self.padding;
        let cost: f32 = cost.iter().sum();
        (
            self.scored() - support,
            (f64::from(cost) / COST_QUANTUM).round(),
        )
    }

    /// Up to `k` points (global indices) taking part in the most scored pairs that support
    /// rotation `m`, most first; points in no supporting pair are left out.
    pub(super) fn anchors(&self, m: &Matrix3<f64>, k: usize) -> Vec<usize> {
        let mut count = vec![0u32; self.points.len()];
        for p in 0..self.scored() {
            if self.normalised_residual2(m, p) < 1.0 {
                let (i, j, _) = self.ranked[p];
                count[i as usize] += 1;
                count[j as usize] += 1;
            }
        }
        let mut order: Vec<usize> = (0..count.len()).filter(|&i| count[i] > 0).collect();
        order.sort_by(|&x, &y| count[y].cmp(&count[x]).then(x.cmp(&y)));
        order.truncate(k);
        order.into_iter().map(|i| self.points[i]).collect()
    }

    /// Rotation vectors solved from up to `count` triangles: a highly ranked pair and one
    /// of its common neighbours, so all three pairs are consistent.
    pub(super) fn seeds(
        &self,
        data: &Correspondences,
        count: usize,
        rng: &mut SeededRng,
    ) -> Vec<[f64; 3]> {
        let mut seeds = Vec::with_capacity(count);
        let pool = self.scored().min(4 * count.max(4));
        if pool == 0 {
            return seeds;
        }
        let (src, dst) = (data.src(), data.dst());
        for _ in 0..count {
            for _ in 0..SEED_TRIES {
                let (i, j, c) = self.ranked[rng.random_range(0..pool)];
                if c == 0 {
                    continue;
                }
                let Some(m) = self.nth_common(i as usize, j as usize, rng.random_range(0..c))
                else {
                    continue;
                };
                let tri = [
                    self.points[i as usize],
                    self.points[j as usize],
                    self.points[m],
                ];
                if let Ok(pose) = arun_pairs(tri.iter().map(|&g| (&src[g], &dst[g], 1.0))) {
                    seeds.push(particle_from_rotation(&pose.rotation));
                    break;
                }
            }
        }
        seeds
    }

    /// The `n`-th (0-based) common neighbour of local points `i` and `j`.
    fn nth_common(&self, i: usize, j: usize, mut n: u32) -> Option<usize> {
        for w in 0..self.words {
            let mut bits = self.rows[i * self.words + w] & self.rows[j * self.words + w];
            let ones = bits.count_ones();
            if n >= ones {
                n -= ones;
                continue;
            }
            for _ in 0..n {
                bits &= bits - 1; // drop the lowest set bit
            }
            return Some(w * 64 + bits.trailing_zeros() as usize);
        }
        None
    }

    /// The largest number of common neighbours a pair of points outside `taken` (global
    /// indices flagged true) has among points outside `taken`: an upper bound on the
    /// evidence for a second motion once the first one's inliers are removed.
    pub(super) fn max_common_outside(&self, taken: &[bool]) -> u32 {
        let mut free = vec![0u64; self.words];
        for (l, &g) in self.points.iter().enumerate() {
            if !taken[g] {
                free[l / 64] |= 1 << (l % 64);
            }
        }
        let is_free = |l: u32| free[l as usize / 64] >> (l % 64) & 1 == 1;
        self.pairs
            .iter()
            .filter(|(i, j, _)| is_free(*i) && is_free(*j))
            .map(|&(i, j, _)| {
                let (ri, rj) = (i as usize * self.words, j as usize * self.words);
                (0..self.words)
                    .map(|w| (self.rows[ri + w] & self.rows[rj + w] & free[w]).count_ones())
                    .sum::<u32>()
            })
            .max()
            .unwrap_or(0)
    }
}

/// The lanes of [`PairGraph::score`]: per lane, the scored pairs supporting rotation `m`
/// and the truncated cost. A [`simd::Kernel`], compiled for the best instruction set of
/// the CPU (the same f32 operations on every lane).
struct Score<'a> {
    graph: &'a PairGraph,
    m: Matrix3<f32>,
}

impl simd::Kernel for Score<'_> {
    type Output = ([u32; LANES], [f32; LANES]);

    #[inline(always)]
    fn run(self) -> Self::Output {
        let (graph, m) = (self.graph, self.m);
        let [ax, ay, az] = &graph.a;
        let [bx, by, bz] = &graph.b;
        // Independent lanes (the arrays are padded to a multiple of LANES), so the
        // compiler can vectorise the sums without reassociating floating point.
        let mut support = [0u32; LANES];
        let mut cost = [0.0f32; LANES];
        let chunks = ax
            .as_chunks::<LANES>()
            .0
            .iter()
            .zip(ay.as_chunks::<LANES>().0)
            .zip(az.as_chunks::<LANES>().0);
        let chunks = chunks.zip(
            bx.as_chunks::<LANES>()
                .0
                .iter()
                .zip(by.as_chunks::<LANES>().0)
                .zip(bz.as_chunks::<LANES>().0),
        );
        for ((((x, y), z), ((u, v), w)), inv) in chunks.zip(graph.inv_tol2.as_chunks::<LANES>().0) {
            for l in 0..LANES {
                let ex = u[l] - (m[(0, 0)] * x[l] + m[(0, 1)] * y[l] + m[(0, 2)] * z[l]);
                let ey = v[l] - (m[(1, 0)] * x[l] + m[(1, 1)] * y[l] + m[(1, 2)] * z[l]);
                let ez = w[l] - (m[(2, 0)] * x[l] + m[(2, 1)] * y[l] + m[(2, 2)] * z[l]);
                let r = (ex * ex + ey * ey + ez * ez) * inv[l];
                support[l] += u32::from(r < 1.0);
                cost[l] += r.min(1.0);
            }
        }
        (support, cost)
    }
}

/// The length-consistent pairs of the points whose coordinates are the columns `s`
/// (source) and `d` (destination), metres, with tolerances `tol`: the adjacency rows
/// (bitsets of `⌈m / 64⌉` words per point) and the pairs `(i, j, 0)`, `i < j`, in
/// lexicographic order. A [`simd::Kernel`], compiled for the best instruction set of the
/// CPU (the same IEEE operations on every pair; the rest is integer).
struct Consistency<'a> {
    s: [&'a [f32]; 3],
    d: [&'a [f32]; 3],
    tol: &'a [f32],
    /// Least source length, metres.
    min_len: f32,
}

impl simd::Kernel for Consistency<'_> {
    type Output = (Vec<u64>, Vec<(u32, u32, u32)>);

    #[inline(always)]
    fn run(self) -> Self::Output {
        let ([sx, sy, sz], [dx, dy, dz], tl, min_len) = (self.s, self.d, self.tol, self.min_len);
        let m = tl.len();
        let words = m.div_ceil(64);
        let mut rows = vec![0u64; m * words];
        let mut consistent = vec![false; m];
        let mut count = 0;
        for li in 0..m {
            let j0 = li + 1;
            let row = &mut consistent[j0..];
            let (ax, ay, az, ti) = (sx[li], sy[li], sz[li], tl[li]);
            let (bx, by, bz) = (dx[li], dy[li], dz[li]);
            let others = sx[j0..]
                .iter()
                .zip(&sy[j0..])
                .zip(&sz[j0..])
                .zip(dx[j0..].iter().zip(&dy[j0..]).zip(&dz[j0..]))
                .zip(&tl[j0..]);
            for (flag, ((((x, y), z), ((u, v), w)), t)) in row.iter_mut().zip(others) {
                let la = ((ax - x) * (ax - x) + (ay - y) * (ay - y) + (az - z) * (az - z)).sqrt();
                let lb = ((bx - u) * (bx - u) + (by - v) * (by - v) + (bz - w) * (bz - w)).sqrt();
                *flag = (la >= min_len) & ((la - lb).abs() < ti + t);
            }
            // The flags 64 at a time as a bitset: into row `li` a word (or two) at a time,
            // shifted to its place, and bit by bit into the rows of the points they name.
            let (upper, lower) = (li * words, li / 64);
            for (c, chunk) in row.chunks(64).enumerate() {
                let mut bits = chunk
                    .iter()
                    .enumerate()
                    .fold(0u64, |b, (k, &f)| b | (u64::from(f) << k));
                count += bits.count_ones() as usize;
                let start = j0 + 64 * c;
                let (word, shift) = (start / 64, start % 64);
                rows[upper + word] |= bits << shift;
                if shift > 0 && bits >> (64 - shift) != 0 {
                    rows[upper + word + 1] |= bits >> (64 - shift);
                }
                while bits != 0 {
                    let lj = start + bits.trailing_zeros() as usize;
                    bits &= bits - 1;
                    rows[lj * words + lower] |= 1 << (li % 64);
                }
            }
        }
        // The pairs: each row's bits above the diagonal, rows in order (their number known,
        // so the list is allocated once).
        let mut pairs = Vec::with_capacity(count);
        if words > 0 {
            for (li, row) in rows.chunks_exact(words).enumerate() {
                let first = (li + 1) / 64;
                for (w, &word) in row.iter().enumerate().skip(first) {
                    let mut bits = if w == first {
                        word & (u64::MAX << ((li + 1) % 64))
                    } else {
                        word
                    };
                    while bits != 0 {
                        let lj = 64 * w + bits.trailing_zeros() as usize;
                        bits &= bits - 1;
                        pairs.push((li as u32, lj as u32, 0));
                    }
                }
            }
        }
        (rows, pairs)
    }
}

/// [`count_common`] compiled for the best instruction set of this CPU
/// ([`simd::dispatch`]; x86-64-v3 has POPCNT: the target's baseline counts bits with a
/// dozen shifts and masks per word). Integer counts: the same in every instruction set.
fn count_common_dispatched(pairs: &mut [(u32, u32, u32)], rows: &[u64], words: usize) {
    /// The call, as a kernel.
    struct Kernel<'a>(&'a mut [(u32, u32, u32)], &'a [u64], usize);
    impl simd::Kernel for Kernel<'_> {
        type Output = ();
        #[inline(always)]
        fn run(self) {
            count_common(self.0, self.1, self.2);
        }
    }
    simd::dispatch(Kernel(pairs, rows, words));
}

/// Sets each pair's common-neighbour count from the adjacency `rows` (`words` words per
/// row). Rows of up to 8 words (512 points; the default keeps 400) take a loop unrolled for
/// their length. Inlined into its callers, so that [`count_common_dispatched`] compiles it
/// for the instruction set it dispatches to.
#[inline(always)]
fn count_common(pairs: &mut [(u32, u32, u32)], rows: &[u64], words: usize) {
    match words {
        1 => count_common_fixed::<1>(pairs, rows),
        2 => count_common_fixed::<2>(pairs, rows),
        3 => count_common_fixed::<3>(pairs, rows),
        4 => count_common_fixed::<4>(pairs, rows),
        5 => count_common_fixed::<5>(pairs, rows),
        6 => count_common_fixed::<6>(pairs, rows),
        7 => count_common_fixed::<7>(pairs, rows),
        8 => count_common_fixed::<8>(pairs, rows),
        _ => {
            for p in pairs {
                let (ri, rj) = (p.0 as usize * words, p.1 as usize * words);
                p.2 = common_count(&rows[ri..ri + words], &rows[rj..rj + words]);
            }
        }
    }
}

/// [`count_common`] for rows of `W` words.
#[inline(always)]
fn count_common_fixed<const W: usize>(pairs: &mut [(u32, u32, u32)], rows: &[u64]) {
    let rows = rows.as_chunks::<W>().0;
    for p in pairs {
        let (a, b) = (&rows[p.0 as usize], &rows[p.1 as usize]);
        p.2 = common_count(a, b);
    }
}

/// Number of bits set in both `a` and `b` (equal lengths): the common neighbours of two
/// adjacency rows. Slices rather than indices, so the loop has no bounds checks and
/// vectorises (integer sums: any order gives the same count).
#[inline(always)]
fn common_count(a: &[u64], b: &[u64]) -> u32 {
    a.iter().zip(b).map(|(x, y)| (x & y).count_ones()).sum()
}

/// The (at most) `max_pairs` pairs with the most common neighbours, in rank order (more
/// first, then by index). Counting sort on the neighbour count: `O(pairs + points)`,
/// deterministic. `pairs` itself is left as it is: the graph keeps every pair for the
/// order-free questions (their count of triangles, the largest count outside a set), so
/// the rest need no compaction (issue 34).
fn ranked_prefix(
    pairs: &[(u32, u32, u32)],
    max_pairs: usize,
    points: usize,
) -> Vec<(u32, u32, u32)> {
    // A total order (each pair once): unstable is the same order, without a buffer.
    let order =
        |x: &(u32, u32, u32), y: &(u32, u32, u32)| y.2.cmp(&x.2).then((x.0, x.1).cmp(&(y.0, y.1)));
    let mut front: Vec<(u32, u32, u32)> = Vec::with_capacity(max_pairs.min(pairs.len()));
    if pairs.len() <= max_pairs {
        front.extend_from_slice(pairs);
        front.sort_unstable_by(order);
        return front;
    }
    let mut histogram = vec![0usize; points + 1];
    for p in pairs {
        histogram[p.2 as usize] += 1;
    }
    // Smallest count `cut` such that the pairs with more than `cut` fit.
    let mut above = 0;
    let mut cut = points;
    while above + histogram[cut] < max_pairs && cut > 0 {
        above += histogram[cut];
        cut -= 1;
    }
    // Pairs above `cut`, then those at `cut` (index order) up to the cap.
    let cut_count = cut as u32;
    front.extend(pairs.iter().copied().filter(|p| p.2 > cut_count));
    let above_cut = front.len();
    front.extend(
        pairs
            .iter()
            .copied()
            .filter(|p| p.2 == cut_count)
            .take(max_pairs - above_cut),
    );
    front.sort_unstable_by(order);
    front
}

#[cfg(test)]
mod tests;
