//! Matching between consecutive frames: mutual nearest neighbours with a ratio test,
//! optionally inside a pixel window, and the circular check of a stereo quadruple.

pub mod subpixel;
pub mod template;

use std::cmp::Ordering::Greater;

use crate::features::{Descriptor, Keypoint};

/// Settings of [`mutual_matches`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct TemporalConfig {
    /// Largest descriptor distance of a match (default 60).
    pub max_distance: f32,
    /// Ratio test: best distance `<` ratio × second best, in both directions (default 0.9).
    pub ratio: f32,
    /// Largest image displacement between the frames, pixels; `None` searches the
    /// whole image (default Some(250)).
    pub max_displacement_px: Option<f32>,
    /// Also require the circular check (left t → right t → right t-1 → left t-1 → left
    /// t closes) (default false).
    pub circular_check: bool,
    /// With a predicted motion between the frames, search each feature's partner only
    /// within this many pixels (column and row) of where the prediction puts it, instead
    /// of within [`TemporalConfig::max_displacement_px`] of where it was
    /// ([`crate::frontend::match_frames_guided`]); `None` never uses a prediction
    /// (default None).
    pub guided_radius_px: Option<f32>,
    /// The guided search is kept when its share of matches (over the fewer of the two
    /// frames' triangulated features) is at least this times the share of the last pair
    /// matched ([`crate::frontend::MotionGuide::last_share`]); below, the prediction is
    /// taken as wrong and the pair searched again without it. A wrong prediction loses
    /// the partners of the points it moves most, the near ones, and the share drops; from
    /// one pair to the next it varies by 0.79-1.0 times on the shared sequences and
    /// variants (docs/history.md, issue 34) (default 0.75).
    pub guided_min_ratio: f32,
}

impl TemporalConfig {
    /// The default settings, usable in constants.
    pub const DEFAULT: Self = Self {
        max_distance: 60.0,
        ratio: 0.9,
        max_displacement_px: Some(250.0),
        circular_check: false,
        guided_radius_px: None,
        guided_min_ratio: 0.75,
    };
}

impl Default for TemporalConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// Best match so far and the two best distances.
type Best = (usize, f32, f32);

/// Indices of `kps` sorted by column (stable), and the sorted columns.
fn by_column(kps: &[Keypoint]) -> (Vec<usize>, Vec<f32>) {
    let mut order: Vec<usize> = (0..kps.len()).collect();
    // Ties by index: the order of a stable sort, without its buffer.
    order.sort_unstable_by(|&i, &j| kps[i].x.total_cmp(&kps[j].x).then(i.cmp(&j)));
    let xs = order.iter().map(|&i| kps[i].x).collect();
    (order, xs)
}

/// `(index, distance)` offered to a best-two search: the first of equal distances wins.
#[inline(always)]
fn offer(best: &mut Best, j: usize, d: f32) {
    if d < best.1 {
        *best = (j, d, best.1);
    } else if d < best.2 {
        best.2 = d;
    }
}

/// For each item of `a`, its best match in `b` and the two best distances, and the same
/// for each item of `b` in `a`. With a window, an item of one set sees those of the
/// other whose column (found through a sorted index) and row are within the window of
/// its own. Each distance is computed once for both directions; each item sees its
/// candidates in the order of the other set's column index, as a search of one direction
/// at a time would. Compiled for the CPU's best instruction set ([`crate::simd`]: the
/// descriptor distances are population counts).
fn nearest_both<D: Descriptor>(
    a_kps: &[Keypoint],
    a: &[D],
    b_kps: &[Keypoint],
    b: &[D],
    window: Option<f32>,
) -> (Vec<Option<Best>>, Vec<Option<Best>>) {
    crate::simd::dispatch(NearestBoth(a_kps, a, b_kps, b, window))
}

/// A call of [`nearest_both`] for [`crate::simd::dispatch`].
struct NearestBoth<'a, D>(
    &'a [Keypoint],
    &'a [D],
    &'a [Keypoint],
    &'a [D],
    Option<f32>,
);

impl<D: Descriptor> crate::simd::Kernel for NearestBoth<'_, D> {
    type Output = (Vec<Option<Best>>, Vec<Option<Best>>);

    #[inline(always)]
    fn run(self) -> Self::Output {
        nearest_both_in(self)
    }
}

/// An item of a during [`nearest_both_in`]: its keypoint, descriptor, index and position
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

/// [`nearest_both`], inlined into each instruction set's compilation.
#[inline(always)]
fn nearest_both_in<D: Descriptor>(
    NearestBoth(a_kps, a, b_kps, b, window): NearestBoth<'_, D>,
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

/// Mutual nearest neighbours between features `a` and `b` (keypoints and descriptors,
/// index-aligned) passing the distance limit and the ratio test in both directions:
/// pairs `(index in a, index in b)` in ascending order of the `a` index.
#[must_use]
pub fn mutual_matches<D: Descriptor>(
    a_kps: &[Keypoint],
    a: &[D],
    b_kps: &[Keypoint],
    b: &[D],
    config: &TemporalConfig,
) -> Vec<(usize, usize)> {
    let (ab, ba) = nearest_both(a_kps, a, b_kps, b, config.max_displacement_px);
    let pass = |m: (usize, f32, f32)| m.1 <= config.max_distance && m.1 < config.ratio * m.2;
    // At most one match per item of `a`.
    let mut out = Vec::with_capacity(ab.len());
    out.extend(ab.iter().enumerate().filter_map(|(i, m)| {
        let m = (*m)?;
        let back = ba[m.0]?;
        (back.0 == i && pass(m) && pass(back)).then_some((i, m.0))
    }));
    out
}

/// The circular check: keeps the left matches `(i, j)` (index `i` into the stereo
/// matches of frame t-1, `j` into those of frame t) that the right images confirm, i.e.
/// the match of the right partners also pairs `i` with `j`. `right` are the matches of
/// the right partners, with the same indexing.
#[must_use]
pub fn circular_check(left: &[(usize, usize)], right: &[(usize, usize)]) -> Vec<(usize, usize)> {
    let mut r = right.to_vec();
    r.sort_unstable();
    left.iter()
        .copied()
        .filter(|m| r.binary_search(m).is_ok())
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::BinaryDescriptor;

    fn kp(x: f32) -> Keypoint {
        Keypoint {
            x,
            y: 0.0,
            scale: 1.0,
            angle: 0.0,
            response: 1.0,
            octave: 0,
        }
    }

    /// The search of one direction at a time, by its definition.
    fn nearest_one_way(
        a_kps: &[Keypoint],
        a: &[BinaryDescriptor],
        b_kps: &[Keypoint],
        b: &[BinaryDescriptor],
        window: Option<f32>,
    ) -> Vec<Option<Best>> {
        let (order, _) = by_column(b_kps);
        a.iter()
            .zip(a_kps)
            .map(|(da, ka)| {
                let mut best = (usize::MAX, f32::INFINITY, f32::INFINITY);
                for &j in &order {
                    let kb = &b_kps[j];
                    if let Some(w) = window
                        && (kb.x < ka.x - w || kb.x > ka.x + w || (ka.y - kb.y).abs() > w)
                    {
                        continue;
                    }
                    offer(&mut best, j, da.distance(&b[j]));
                }
                (best.0 != usize::MAX).then_some(best)
            })
            .collect()
    }

    #[test]
    fn both_directions_at_once_match_one_at_a_time() {
        let mut g = crate::test_noise::Lcg(5);
        let mut next = || g.next_u32() >> 8;
        let mut set = |n: usize| -> (Vec<Keypoint>, Vec<BinaryDescriptor>) {
            (0..n)
                .map(|_| {
                    // Few distinct bits (many equal distances) and quarter-pixel columns.
                    let mut k = kp((next() % 400) as f32 * 0.25);
                    k.y = (next() % 60) as f32 * 0.5;
                    (k, BinaryDescriptor([(next() % 8) as u8; 32]))
                })
                .unzip()
        };
        let (ka, a) = set(300);
        let (kb, b) = set(250);
        for window in [
            None,
            Some(-1.0),
            Some(0.0),
            Some(0.25),
            Some(7.5),
            Some(20.0),
            Some(1000.0),
        ] {
            let (ab, ba) = nearest_both(&ka, &a, &kb, &b, window);
            assert_eq!(ab, nearest_one_way(&ka, &a, &kb, &b, window), "{window:?}");
            assert_eq!(ba, nearest_one_way(&kb, &b, &ka, &a, window), "{window:?}");
        }
    }

    #[test]
    fn mutual_and_circular() {
        let d = |b: u8| BinaryDescriptor([b; 32]);
        let a = [d(0b0000_0000), d(0b1111_0000)];
        let b = [d(0b1111_0001), d(0b0000_0001)];
        let ka = [kp(0.0), kp(1.0)];
        let m = mutual_matches(&ka, &a, &ka, &b, &TemporalConfig::default());
        assert_eq!(m, vec![(0, 1), (1, 0)]);
        assert_eq!(circular_check(&m, &[(1, 0), (0, 0)]), vec![(1, 0)]);
    }
}
