//! [`super::nearest_both`] against its earlier form, bit for bit (issue 34): the distances
//! of a run of candidates at once ([`Descriptor::distances`]), the offers of a run skipped
//! when none could change a best match, in both compilations ([`crate::simd`]).

use std::cmp::Ordering::Greater;

use super::{Best, by_column, nearest_both, offer};
use crate::features::{BinaryDescriptor, Descriptor, FloatDescriptor64, Keypoint};
use crate::simd::baseline;
use crate::test_noise::Lcg;

/// An item of a during [`nearest_both_before`]: its keypoint, descriptor, index and position
/// in column order, and the window.
struct A<'a, D> {
    ka: &'a Keypoint,
    da: &'a D,
    i: usize,
    pos: usize,
    window: Option<f32>,
}

impl<D: Descriptor> A<'_, D> {
    /// Offers the distance to each of `items` (items of b in column order, with the range
    /// of a's positions each sees) to the item's best match (`bests`, the same length)
    /// and, when `A_SEES` (the items are in a's window), to a's (`best`). An item beyond
    /// the window's rows offers nothing.
    #[inline(always)]
    fn scan<const A_SEES: bool>(
        &self,
        items: &[(usize, f32, (usize, usize), &D)],
        bests: &mut [Best],
        best: &mut Best,
    ) {
        let A {
            ka,
            da,
            i,
            pos,
            window,
        } = *self;
        for (&(j, yb, (ra, rb), db), best_j) in items.iter().zip(bests) {
            // Not beyond the window (a NaN row is not beyond it, as before).
            let rows = window.is_none_or(|w| (ka.y - yb).abs().partial_cmp(&w) != Some(Greater));
            let b_sees = rows && pos >= ra && pos < rb;
            // Without branches on the window (they are unpredictable): a distance out
            // of the window is infinite, which changes no best.
            let d = da.distance(db);
            if A_SEES {
                offer(best, j, if rows { d } else { f32::INFINITY });
            }
            offer(best_j, i, if b_sees { d } else { f32::INFINITY });
        }
    }
}

/// [`super::nearest_both`] as it was before the distances were computed a run at a time
/// and the offers checked a run at a time.
fn nearest_both_before<D: Descriptor>(
    a_kps: &[Keypoint],
    a: &[D],
    b_kps: &[Keypoint],
    b: &[D],
    window: Option<f32>,
) -> (Vec<Option<Best>>, Vec<Option<Best>>) {
    let (order_a, xs_a) = by_column(a_kps);
    let (order_b, xs_b) = by_column(b_kps);
    // The range of a's sorted positions that each item of b sees.
    let a_range: Vec<(usize, usize)> = match window {
        Some(w) => b_kps
            .iter()
            .map(|kb| {
                (
                    xs_a.partition_point(|&x| x < kb.x - w),
                    xs_a.partition_point(|&x| x <= kb.x + w),
                )
            })
            .collect(),
        None => vec![(0, xs_a.len()); b_kps.len()],
    };
    // Items of b in column order, contiguous, with the range of a's sorted positions each
    // sees; their best matches in the same order (`best_b_sorted[k]` is item `k`'s).
    let b_sorted: Vec<(usize, f32, (usize, usize), &D)> = order_b
        .iter()
        .map(|&j| (j, b_kps[j].y, a_range[j], &b[j]))
        .collect();
    let none = (usize::MAX, f32::INFINITY, f32::INFINITY);
    let mut best_a = vec![none; a.len()];
    let mut best_b_sorted = vec![none; b_sorted.len()];
    for (pos, &i) in order_a.iter().enumerate() {
        let (ka, da) = (&a_kps[i], &a[i]);
        let (lo, hi, scan) = match window {
            Some(w) => {
                let (lo, hi) = (
                    xs_b.partition_point(|&x| x < ka.x - w),
                    xs_b.partition_point(|&x| x <= ka.x + w),
                );
                // Wider by a pixel, for the items of b that see this one through their
                // own rounding of the window.
                let scan = (
                    xs_b.partition_point(|&x| x < ka.x - w - 1.0).min(lo),
                    xs_b.partition_point(|&x| x <= ka.x + w + 1.0).max(hi),
                );
                (lo, hi, scan)
            }
            None => (0, b_sorted.len(), (0, b_sorted.len())),
        };
        let best = &mut best_a[i];
        // The scan in three parts, in column order: a sees the middle one's items only
        // (`lo..hi`, empty when the window is), the scan's extra items either side only
        // see a (when their own window holds it).
        let mid_lo = lo.clamp(scan.0, scan.1.max(scan.0));
        let mid_hi = hi.clamp(mid_lo, scan.1.max(mid_lo));
        let one = A {
            ka,
            da,
            i,
            pos,
            window,
        };
        for (range, a_sees) in [
            (scan.0..mid_lo, false),
            (mid_lo..mid_hi, true),
            (mid_hi..scan.1, false),
        ] {
            // The items and their best matches, as slices of one length (no bounds check
            // per item); none when the range is empty.
            let (Some(items), Some(bests)) =
                (b_sorted.get(range.clone()), best_b_sorted.get_mut(range))
            else {
                continue;
            };
            if a_sees {
                one.scan::<true>(items, bests, best);
            } else {
                one.scan::<false>(items, bests, best);
            }
        }
    }
    let found = |m: Best| (m.0 != usize::MAX).then_some(m);
    // Back from column order to b's order.
    let mut found_b = vec![None; b.len()];
    for (&(j, ..), &m) in b_sorted.iter().zip(&best_b_sorted) {
        found_b[j] = found(m);
    }
    (best_a.into_iter().map(found).collect(), found_b)
}

/// The bests as bits (a NaN or a signed zero compares as itself).
fn bits(m: &[Option<Best>]) -> Vec<Option<(usize, u32, u32)>> {
    m.iter()
        .map(|m| m.map(|(j, d1, d2)| (j, d1.to_bits(), d2.to_bits())))
        .collect()
}

/// `n` keypoints on quarter-pixel columns and half-pixel rows (many equal columns), some
/// of them at a NaN column or row.
fn keypoints(g: &mut Lcg, n: usize) -> Vec<Keypoint> {
    (0..n)
        .map(|_| {
            let (r, c) = (g.next_u32() >> 8, g.next_u32() >> 8);
            let nan = r.is_multiple_of(97);
            Keypoint {
                x: if nan && c.is_multiple_of(2) {
                    f32::NAN
                } else {
                    (c % 600) as f32 * 0.25
                },
                y: if nan && c % 2 == 1 {
                    f32::NAN
                } else {
                    (r % 80) as f32 * 0.5
                },
                scale: 1.0,
                angle: 0.0,
                response: 1.0,
                octave: 0,
            }
        })
        .collect()
}

/// `n` binary descriptors: few distinct (many duplicates and equal distances) when
/// `few`, otherwise random bits.
fn binary(g: &mut Lcg, n: usize, few: bool) -> Vec<BinaryDescriptor> {
    (0..n)
        .map(|_| {
            let mut d = [0u8; 32];
            for b in &mut d {
                *b = (g.next_u32() >> 24) as u8;
            }
            if few {
                d = [d[0] % 4; 32];
                d[7] = (g.next_u32() >> 30) as u8;
            }
            BinaryDescriptor(d)
        })
        .collect()
}

const WINDOWS: [Option<f32>; 9] = [
    None,
    Some(-3.0),
    Some(-1.0),
    Some(0.0),
    Some(0.25),
    Some(7.5),
    Some(40.0),
    Some(1000.0),
    Some(f32::NAN),
];

/// Both compilations of [`nearest_both`] against [`nearest_both_before`], both ways.
fn check<D: Descriptor>(ka: &[Keypoint], a: &[D], kb: &[Keypoint], b: &[D]) {
    for window in WINDOWS {
        for ((ka, a), (kb, b)) in [((ka, a), (kb, b)), ((kb, b), (ka, a))] {
            let (want_ab, want_ba) = nearest_both_before(ka, a, kb, b, window);
            let (ab, ba) = nearest_both(ka, a, kb, b, window);
            let (base_ab, base_ba) = baseline(|| nearest_both(ka, a, kb, b, window));
            assert_eq!(bits(&ab), bits(&want_ab), "{window:?}");
            assert_eq!(bits(&ba), bits(&want_ba), "{window:?}");
            assert_eq!(bits(&base_ab), bits(&want_ab), "{window:?}");
            assert_eq!(bits(&base_ba), bits(&want_ba), "{window:?}");
        }
    }
}

/// Binary descriptors (duplicates, equal distances, random bits), sets of all sizes
/// around a run's length.
#[test]
fn binary_matches_are_those_of_before() {
    let mut g = Lcg(36);
    let mut found = 0;
    for (na, nb) in [(0, 5), (1, 1), (7, 9), (8, 16), (17, 23), (300, 250)] {
        for few in [true, false] {
            let (ka, kb) = (keypoints(&mut g, na), keypoints(&mut g, nb));
            let (a, b) = (binary(&mut g, na, few), binary(&mut g, nb, few));
            check(&ka, &a, &kb, &b);
            found += nearest_both(&ka, &a, &kb, &b, Some(7.5))
                .0
                .iter()
                .flatten()
                .count();
        }
    }
    assert!(found > 400, "{found} found");
}

/// Real descriptors (the default [`Descriptor::distances`]), some with NaN components
/// (NaN distances, which change no best) and signed zeros.
#[test]
fn float_matches_are_those_of_before() {
    let mut g = Lcg(37);
    let mut set = |n: usize| -> (Vec<Keypoint>, Vec<FloatDescriptor64>) {
        let k = keypoints(&mut g, n);
        let d = (0..n)
            .map(|_| {
                let mut d = [0f32; 64];
                let r = g.next_u32();
                d[0] = ((r >> 8) % 3) as f32;
                d[1] = if r.is_multiple_of(2) { 0.0 } else { -0.0 };
                if r.is_multiple_of(23) {
                    d[2] = f32::NAN;
                }
                FloatDescriptor64(d)
            })
            .collect();
        (k, d)
    };
    let (ka, a) = set(120);
    let (kb, b) = set(90);
    check(&ka, &a, &kb, &b);
}

/// A run of binary distances is the distances one at a time, in both compilations.
#[test]
fn binary_distances_are_one_at_a_time() {
    struct Run<'a>(&'a BinaryDescriptor, &'a [BinaryDescriptor]);
    impl crate::simd::Kernel for Run<'_> {
        type Output = Vec<f32>;
        #[inline(always)]
        fn run(self) -> Vec<f32> {
            let mut out = vec![-1.0; self.1.len()];
            self.0.distances(self.1, &mut out);
            out
        }
    }
    let mut g = Lcg(38);
    let others = binary(&mut g, 200, false);
    for (k, a) in binary(&mut g, 6, false).iter().enumerate() {
        let a = if k == 0 {
            &BinaryDescriptor([0; 32])
        } else {
            a
        };
        let want: Vec<u32> = others.iter().map(|b| a.distance(b).to_bits()).collect();
        let run = || crate::simd::dispatch(Run(a, &others));
        let got: Vec<u32> = run().iter().map(|d| d.to_bits()).collect();
        let base: Vec<u32> = baseline(run).iter().map(|d| d.to_bits()).collect();
        assert_eq!(got, want);
        assert_eq!(base, want);
    }
    let mut out = [0f32; 3];
    BinaryDescriptor([0xff; 32]).distances(&others[..2], &mut out);
    assert_eq!(out[2], 0.0, "only as many as the shorter slice");
}
