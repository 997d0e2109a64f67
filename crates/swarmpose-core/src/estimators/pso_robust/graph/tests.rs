//! Tests of the consistency graph.

use super::*;
use crate::rng::seeded;

/// `rank_prefix` as it was before the in-place compaction (issue 34): the reference. It
/// reorders `pairs` (the ranked prefix first, then the rest in their order); the graph
/// now keeps the ranked prefix apart ([`ranked_prefix`]) and every pair as built.
fn rank_prefix_reference(pairs: &mut [(u32, u32, u32)], max_pairs: usize, points: usize) -> usize {
    let order =
        |x: &(u32, u32, u32), y: &(u32, u32, u32)| y.2.cmp(&x.2).then((x.0, x.1).cmp(&(y.0, y.1)));
    if pairs.len() <= max_pairs {
        pairs.sort_unstable_by(order);
        return pairs.len();
    }
    let mut histogram = vec![0usize; points + 1];
    for p in pairs.iter() {
        histogram[p.2 as usize] += 1;
    }
    let mut above = 0;
    let mut cut = points;
    while above + histogram[cut] < max_pairs && cut > 0 {
        above += histogram[cut];
        cut -= 1;
    }
    let mut front: Vec<(u32, u32, u32)> = Vec::with_capacity(max_pairs.min(pairs.len()));
    front.extend(pairs.iter().copied().filter(|p| p.2 > cut as u32));
    front.extend(
        pairs
            .iter()
            .copied()
            .filter(|p| p.2 == cut as u32)
            .take(max_pairs - front.len()),
    );
    front.sort_unstable_by(order);
    let n = front.len();
    let mut rest: Vec<(u32, u32, u32)> = Vec::with_capacity(pairs.len() - n);
    let mut taken_at_cut = n - pairs.iter().filter(|p| p.2 > cut as u32).count();
    for p in pairs.iter() {
        if p.2 > cut as u32 {
            continue;
        }
        if p.2 == cut as u32 && taken_at_cut > 0 {
            taken_at_cut -= 1;
            continue;
        }
        rest.push(*p);
    }
    pairs[..n].copy_from_slice(&front);
    pairs[n..].copy_from_slice(&rest);
    n
}

#[test]
fn ranked_prefix_matches_the_reference_on_random_pairs() {
    let mut rng = seeded(34);
    for case in 0..300 {
        let points: usize = rng.random_range(2..60);
        let len: usize = rng.random_range(0..400);
        // Few distinct counts in some cases, so that ties at the cut are common.
        let top = if case % 2 == 0 { 3 } else { points as u32 }.min(points as u32 - 1);
        let mut pairs: Vec<(u32, u32, u32)> = (0..len)
            .map(|_| {
                let i = rng.random_range(0..points as u32);
                (
                    i,
                    rng.random_range(0..points as u32),
                    rng.random_range(0..=top),
                )
            })
            .collect();
        if case % 3 == 0 {
            pairs.sort_unstable_by_key(|p| (p.0, p.1));
        }
        let max_pairs = rng.random_range(1..=len.max(1) + 2);
        let mut expected = pairs.clone();
        let n_expected = rank_prefix_reference(&mut expected, max_pairs, points);
        let before = pairs.clone();
        let ranked = ranked_prefix(&pairs, max_pairs, points);
        assert_eq!(ranked, expected[..n_expected], "case {case}");
        assert_eq!(pairs, before, "case {case}: the pairs are left as they are");
    }
}

#[test]
fn count_common_matches_the_indexed_sum_for_every_row_length() {
    let mut rng = seeded(36);
    for words in 0..12 {
        let m = 64 * words.max(1);
        let rows: Vec<u64> = (0..m * words)
            .map(|k| match k % 7 {
                0 => 0,
                1 => u64::MAX,
                _ => rng.random(),
            })
            .collect();
        let mut pairs: Vec<(u32, u32, u32)> = (0..300)
            .map(|_| {
                let i = rng.random_range(0..m as u32);
                (i, rng.random_range(0..m as u32), u32::MAX)
            })
            .collect();
        let mut dispatched = pairs.clone();
        count_common(&mut pairs, &rows, words);
        count_common_dispatched(&mut dispatched, &rows, words);
        assert_eq!(pairs, dispatched, "{words} words: baseline and dispatched");
        for &(i, j, c) in &pairs {
            let (ri, rj) = (i as usize * words, j as usize * words);
            let expected: u32 = (0..words)
                .map(|w| (rows[ri + w] & rows[rj + w]).count_ones())
                .sum();
            assert_eq!(c, expected, "{words} words, pair ({i}, {j})");
        }
    }
}

#[test]
fn common_count_matches_the_indexed_sum() {
    let mut rng = seeded(35);
    for _ in 0..200 {
        let words: usize = rng.random_range(0..40);
        let rows: Vec<u64> = (0..2 * words)
            .map(|k| match k % 5 {
                0 => 0,
                1 => u64::MAX,
                _ => rng.random(),
            })
            .collect();
        let expected: u32 = (0..words)
            .map(|w| (rows[w] & rows[words + w]).count_ones())
            .sum();
        assert_eq!(common_count(&rows[..words], &rows[words..]), expected);
    }
}

#[test]
fn ranked_prefix_keeps_the_best() {
    let pairs: Vec<(u32, u32, u32)> = (0..10)
        .map(|k| (k, k + 1, [3, 7, 1, 7, 0, 5, 5, 2, 9, 5][k as usize]))
        .collect();
    let ranked = ranked_prefix(&pairs, 4, 20);
    let counts: Vec<u32> = ranked.iter().map(|p| p.2).collect();
    assert_eq!(counts, vec![9, 7, 7, 5]);
    assert_eq!(ranked[3], (5, 6, 5)); // first of the tied 5s by index
    // Fewer pairs than the cap: all of them, ranked.
    let all = ranked_prefix(&pairs, 10, 20);
    let counts: Vec<u32> = all.iter().map(|p| p.2).collect();
    assert_eq!(counts, vec![9, 7, 7, 5, 5, 5, 3, 2, 1, 0]);
}

/// A graph built as before the ranked prefix was kept apart (issue 34): the reference
/// consistency loop and the reference ranking, whose reordered pairs answer the
/// order-free questions (triangles, the largest count outside a set).
#[test]
fn graph_matches_the_reference_ranking() {
    use nalgebra::Point3;
    let mut rng = seeded(40);
    for case in 0..40 {
        let n: usize = rng.random_range(5..150);
        let src: Vec<Point3<f64>> = (0..n)
            .map(|_| {
                Point3::new(
                    rng.random_range(-5.0..5.0),
                    rng.random_range(-2.0..2.0),
                    rng.random_range(2.0..20.0),
                )
            })
            .collect();
        // Half the rows moved rigidly (a shift), the rest anywhere: a dense cluster.
        let dst: Vec<Point3<f64>> = src
            .iter()
            .map(|p| {
                if rng.random_range(0..2) == 0 {
                    p + nalgebra::Vector3::new(0.5, 0.0, -1.0)
                } else {
                    Point3::new(
                        rng.random_range(-5.0..5.0),
                        rng.random_range(-2.0..2.0),
                        rng.random_range(2.0..20.0),
                    )
                }
            })
            .collect();
        let data = Correspondences::new(src.clone(), dst.clone()).expect("valid");
        let max_pairs = [4, 50, 256, 100_000][case % 4];
        let points: Vec<usize> = (0..n).collect();
        let graph = PairGraph::build(&data, points, Tolerance::Uniform(0.3), max_pairs, 0.5);
        // The reference.
        let column = |f: &dyn Fn(usize) -> f64| (0..n).map(|g| f(g) as f32).collect::<Vec<_>>();
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
        let tl = vec![0.3f32; n];
        let (rows, mut pairs) = consistency_reference([&sx, &sy, &sz], [&dx, &dy, &dz], &tl, 0.5);
        let words = n.div_ceil(64);
        for p in &mut pairs {
            let (ri, rj) = (p.0 as usize * words, p.1 as usize * words);
            p.2 = (0..words)
                .map(|w| (rows[ri + w] & rows[rj + w]).count_ones())
                .sum();
        }
        let scored = rank_prefix_reference(&mut pairs, max_pairs, n);
        assert_eq!(graph.rows, rows, "case {case}");
        assert_eq!(graph.ranked, pairs[..scored], "case {case}");
        assert_eq!(graph.scored(), scored, "case {case}");
        let triangles = pairs.iter().map(|p| u64::from(p.2)).sum::<u64>() / 3;
        assert_eq!(graph.triangles(), triangles, "case {case}");
        for _ in 0..5 {
            let taken: Vec<bool> = (0..n).map(|_| rng.random_range(0..3) == 0).collect();
            let free = |l: u32| !taken[l as usize];
            let expected = pairs
                .iter()
                .filter(|(i, j, _)| free(*i) && free(*j))
                .map(|&(i, j, _)| {
                    (0..n as u32)
                        .filter(|&l| free(l))
                        .filter(|&l| {
                            let bit =
                                |a: u32| rows[a as usize * words + l as usize / 64] >> (l % 64) & 1;
                            bit(i) == 1 && bit(j) == 1
                        })
                        .count() as u32
                })
                .max()
                .unwrap_or(0);
            assert_eq!(graph.max_common_outside(&taken), expected, "case {case}");
        }
    }
}

/// The consistency loop as it was before the bitset scan and the dispatch (issue 34): the
/// reference.
fn consistency_reference(
    s: [&[f32]; 3],
    d: [&[f32]; 3],
    tl: &[f32],
    min_len: f32,
) -> (Vec<u64>, Vec<(u32, u32, u32)>) {
    let ([sx, sy, sz], [dx, dy, dz]) = (s, d);
    let m = tl.len();
    let words = m.div_ceil(64);
    let mut rows = vec![0u64; m * words];
    let mut pairs = Vec::new();
    let mut consistent = vec![false; m];
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
        for (k, _) in row.iter().enumerate().filter(|(_, f)| **f) {
            let lj = j0 + k;
            rows[li * words + lj / 64] |= 1 << (lj % 64);
            rows[lj * words + li / 64] |= 1 << (li % 64);
            pairs.push((li as u32, lj as u32, 0));
        }
    }
    (rows, pairs)
}

#[test]
fn consistency_matches_the_reference_in_every_instruction_set() {
    let mut rng = seeded(38);
    for case in 0..60 {
        let m: usize = rng.random_range(0..300);
        let value = |rng: &mut SeededRng, scale: f32| -> f32 {
            match rng.random_range(0..200) {
                0 => 0.0,
                1 => -0.0,
                2 => f32::NAN,
                3 => f32::INFINITY,
                _ => rng.random_range(-scale..scale),
            }
        };
        // Clustered values, so that many pairs are consistent.
        let scale = if case % 2 == 0 { 2.0 } else { 20.0 };
        let columns: Vec<Vec<f32>> = (0..6)
            .map(|_| (0..m).map(|_| value(&mut rng, scale)).collect())
            .collect();
        let tl: Vec<f32> = (0..m).map(|_| rng.random_range(0.0..1.5)).collect();
        let c: Vec<&[f32]> = columns.iter().map(Vec::as_slice).collect();
        let (s, d) = ([c[0], c[1], c[2]], [c[3], c[4], c[5]]);
        let min_len = [0.0, 0.5, 3.0][case % 3];
        let kernel = || Consistency {
            s,
            d,
            tol: &tl,
            min_len,
        };
        let expected = consistency_reference(s, d, &tl, min_len);
        assert_eq!(simd::dispatch(kernel()), expected, "case {case}");
        assert_eq!(
            simd::baseline(|| simd::dispatch(kernel())),
            expected,
            "case {case}"
        );
    }
}

#[test]
fn scores_have_the_same_bits_in_every_instruction_set() {
    use nalgebra::{Isometry3, Point3, Vector3};
    let mut rng = seeded(39);
    for case in 0..20 {
        let n: usize = rng.random_range(10..200);
        let truth = Isometry3::new(
            Vector3::new(0.3, -0.1, 1.0),
            Vector3::new(0.02, rng.random_range(-0.2..0.2), 0.01),
        );
        let src: Vec<Point3<f64>> = (0..n)
            .map(|_| {
                Point3::new(
                    rng.random_range(-10.0..10.0),
                    rng.random_range(-2.0..2.0),
                    rng.random_range(4.0..40.0),
                )
            })
            .collect();
        let dst: Vec<Point3<f64>> = src
            .iter()
            .map(|p| {
                if rng.random_range(0..3) == 0 {
                    Point3::new(rng.random_range(-10.0..10.0), 0.0, 20.0)
                } else {
                    truth * p + Vector3::new(rng.random_range(-0.05..0.05), 0.0, 0.0)
                }
            })
            .collect();
        let data = Correspondences::new(src, dst).expect("valid");
        let graph = PairGraph::build(&data, (0..n).collect(), Tolerance::Uniform(0.1), 500, 0.0);
        assert!(graph.scored() > 0, "case {case}: no scored pair");
        for _ in 0..20 {
            let axis = Vector3::new(
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
                rng.random_range(-0.3..0.3),
            );
            let q = if case % 4 == 0 {
                truth.rotation
            } else {
                UnitQuaternion::from_scaled_axis(axis)
            };
            // The lanes themselves (the score rounds the cost), and the score.
            let m: Matrix3<f32> = q.to_rotation_matrix().into_inner().cast::<f32>();
            let kernel = || Score { graph: &graph, m };
            let lanes = |(s, c): ([u32; LANES], [f32; LANES])| (s, c.map(f32::to_bits));
            assert_eq!(
                lanes(simd::dispatch(kernel())),
                lanes(simd::baseline(|| simd::dispatch(kernel()))),
                "case {case}"
            );
            let (a, b) = (graph.score(&q), simd::baseline(|| graph.score(&q)));
            assert_eq!((a.0, a.1.to_bits()), (b.0, b.1.to_bits()), "case {case}");
        }
    }
}
