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

/// Candidates whose offers are checked at once: when none of a run of this many would
/// change a best match (the usual case, once the best matches have settled), the run
/// offers nothing, without a branch per candidate.
const RUN: usize = 8;

/// The items of b in column order, as columns: their indices, rows, the range of a's
/// sorted positions each sees, and descriptors; and their best matches so far (index, best
/// and second best distance).
struct SortedB<D> {
    j: Vec<usize>,
    y: Vec<f32>,
    lo: Vec<usize>,
    hi: Vec<usize>,
    d: Vec<D>,
    best_i: Vec<usize>,
    best_1: Vec<f32>,
    best_2: Vec<f32>,
}

/// `(index, distance)` offered to a best-two search kept in three places: [`offer`].
#[inline(always)]
fn offer_parts(best: (&mut usize, &mut f32, &mut f32), j: usize, d: f32) {
    let mut b = (*best.0, *best.1, *best.2);
    offer(&mut b, j, d);
    (*best.0, *best.1, *best.2) = b;
}

/// Whether a candidate's row is within the window `w` of `y` (a NaN row is, and every
/// row is without a window: `w` infinite).
#[inline(always)]
fn rows_within(y: f32, yb: f32, w: f32) -> bool {
    (y - yb).abs().partial_cmp(&w) != Some(Greater)
}

/// Offers the candidates `js` (rows `ys`, distances `ds`, the same length) in order to a's
/// best match `best`; a candidate beyond the window's rows (`w`) offers nothing. A run of
/// candidates none of which is below the second best distance at its start is skipped: its
/// offers would change nothing (the second best only decreases).
#[inline(always)]
fn offer_to_a(best: &mut Best, (y, w): (f32, f32), js: &[usize], ys: &[f32], ds: &[f32]) {
    let one = |best: &mut Best, j: usize, yb: f32, d: f32| {
        offer(
            best,
            j,
            if rows_within(y, yb, w) {
                d
            } else {
                f32::INFINITY
            },
        );
    };
    let (jr, yr, dr) = (
        js.chunks_exact(RUN),
        ys.chunks_exact(RUN),
        ds.chunks_exact(RUN),
    );
    let rest = (jr.remainder(), yr.remainder(), dr.remainder());
    for ((jc, yc), dc) in jr.zip(yr).zip(dr) {
        let limit = best.2;
        let any = yc.iter().zip(dc).fold(false, |any, (&yb, &d)| {
            any | (rows_within(y, yb, w) & (d < limit))
        });
        if any {
            for ((&j, &yb), &d) in jc.iter().zip(yc).zip(dc) {
                one(best, j, yb, d);
            }
        }
    }
    for ((&j, &yb), &d) in rest.0.iter().zip(rest.1).zip(rest.2) {
        one(best, j, yb, d);
    }
}

impl<D> SortedB<D> {
    /// Offers item `i` of a (row `y`, sorted position `pos`; window `w`) at distances `ds`
    /// to the items of b from `start` on (as many as `ds` holds), each seeing it within its
    /// own window only. A run of items none of which sees it below its own second best
    /// distance is skipped (their offers would change nothing).
    #[inline(always)]
    fn offer_to_b(&mut self, (i, pos, y, w): (usize, usize, f32, f32), start: usize, ds: &[f32]) {
        let end = start + ds.len();
        let (Some(ys), Some(lo), Some(hi)) = (
            self.y.get(start..end),
            self.lo.get(start..end),
            self.hi.get(start..end),
        ) else {
            return;
        };
        let (Some(bi), Some(b1), Some(b2)) = (
            self.best_i.get_mut(start..end),
            self.best_1.get_mut(start..end),
            self.best_2.get_mut(start..end),
        ) else {
            return;
        };
        let sees = |yb: f32, lo: usize, hi: usize| rows_within(y, yb, w) & (pos >= lo) & (pos < hi);
        // The items of one run (slices of one length): their offers, when one of them
        // could change a best match (`check`), or always.
        let run =
            |ys: &[f32],
             lo: &[usize],
             hi: &[usize],
             ds: &[f32],
             (bi, b1, b2): (&mut [usize], &mut [f32], &mut [f32]),
             check: bool| {
                let any =
                    !check
                        || ys.iter().zip(lo).zip(hi).zip(ds).zip(&*b2).fold(
                            false,
                            |any, ((((&yb, &lo), &hi), &d), &b2)| {
                                any | (sees(yb, lo, hi) & (d < b2))
                            },
                        );
                if any {
                    let items = ys.iter().zip(lo).zip(hi).zip(ds);
                    let bests = bi.iter_mut().zip(b1.iter_mut()).zip(b2.iter_mut());
                    for ((((&yb, &lo), &hi), &d), ((bi, b1), b2)) in items.zip(bests) {
                        // The others' offers would change nothing.
                        if sees(yb, lo, hi) & (d < *b2) {
                            offer_parts((bi, b1, b2), i, d);
                        }
                    }
                }
            };
        let full = ds.len() / RUN * RUN;
        let (ys, ys_rest) = ys.split_at(full);
        let (lo, lo_rest) = lo.split_at(full);
        let (hi, hi_rest) = hi.split_at(full);
        let (ds, ds_rest) = ds.split_at(full);
        let (bi, bi_rest) = bi.split_at_mut(full);
        let (b1, b1_rest) = b1.split_at_mut(full);
        let (b2, b2_rest) = b2.split_at_mut(full);
        let items = ys
            .chunks_exact(RUN)
            .zip(lo.chunks_exact(RUN))
            .zip(hi.chunks_exact(RUN))
            .zip(ds.chunks_exact(RUN));
        let bests = bi
            .chunks_exact_mut(RUN)
            .zip(b1.chunks_exact_mut(RUN))
            .zip(b2.chunks_exact_mut(RUN));
        for ((((ys, lo), hi), ds), ((bi, b1), b2)) in items.zip(bests) {
            run(ys, lo, hi, ds, (bi, b1, b2), true);
        }
        run(
            ys_rest,
            lo_rest,
            hi_rest,
            ds_rest,
            (bi_rest, b1_rest, b2_rest),
            false,
        );
    }
}

/// [`nearest_both`], inlined into each instruction set's compilation. For each item of a
/// (in column order) the distances to the items of b its scan covers are computed at once
/// ([`Descriptor::distances`]), then offered to a's best match (the items in a's window)
/// and to each item's (those whose window holds a), in the scan's order.
#[inline(always)]
fn nearest_both_in<D: Descriptor>(
    NearestBoth(a_kps, a, b_kps, b, window): NearestBoth<'_, D>,
) -> (Vec<Option<Best>>, Vec<Option<Best>>) {
    let (order_a, xs_a) = by_column(a_kps);
    let (order_b, xs_b) = by_column(b_kps);
    // The range of a's sorted positions that each item of b sees.
    let a_range = |kb: &Keypoint| match window {
        Some(w) => (
            xs_a.partition_point(|&x| x < kb.x - w),
            xs_a.partition_point(|&x| x <= kb.x + w),
        ),
        None => (0, xs_a.len()),
    };
    let n_b = order_b.len().min(b.len());
    let mut sb = SortedB {
        j: order_b.clone(),
        y: order_b.iter().map(|&j| b_kps[j].y).collect(),
        lo: Vec::with_capacity(n_b),
        hi: Vec::with_capacity(n_b),
        d: order_b.iter().map(|&j| b[j].clone()).collect(),
        best_i: vec![usize::MAX; n_b],
        best_1: vec![f32::INFINITY; n_b],
        best_2: vec![f32::INFINITY; n_b],
    };
    for &j in &order_b {
        let (lo, hi) = a_range(&b_kps[j]);
        sb.lo.push(lo);
        sb.hi.push(hi);
    }
    // Without a window every row is within it.
    let w_rows = window.unwrap_or(f32::INFINITY);
    let mut best_a = vec![(usize::MAX, f32::INFINITY, f32::INFINITY); a.len()];
    let mut dist = vec![0f32; n_b];
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
            None => (0, n_b, (0, n_b)),
        };
        // a sees the items `lo..hi` of the scan (none when the window is empty); the scan's
        // extra items either side only see a (when their own window holds it).
        let mid_lo = lo.clamp(scan.0, scan.1.max(scan.0));
        let mid_hi = hi.clamp(mid_lo, scan.1.max(mid_lo));
        let (Some(descs), Some(ds)) = (
            sb.d.get(scan.0..scan.1),
            dist.get_mut(..scan.1.saturating_sub(scan.0)),
        ) else {
            continue;
        };
        da.distances(descs, ds);
        let ds = &*ds;
        if let (Some(js), Some(ys), Some(dm)) = (
            sb.j.get(mid_lo..mid_hi),
            sb.y.get(mid_lo..mid_hi),
            ds.get(mid_lo - scan.0..mid_hi - scan.0),
        ) {
            offer_to_a(&mut best_a[i], (ka.y, w_rows), js, ys, dm);
        }
        sb.offer_to_b((i, pos, ka.y, w_rows), scan.0, ds);
    }
    let found = |m: Best| (m.0 != usize::MAX).then_some(m);
    // Back from column order to b's order.
    let mut found_b = vec![None; b.len()];
    for (k, &j) in sb.j.iter().enumerate().take(n_b) {
        found_b[j] = found((sb.best_i[k], sb.best_1[k], sb.best_2[k]));
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
mod scan_bits;

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
