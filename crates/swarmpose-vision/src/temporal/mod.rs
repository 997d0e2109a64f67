//! Matching between consecutive frames: mutual nearest neighbours with a ratio test,
//! optionally inside a pixel window, and the circular check of a stereo quadruple.

pub mod subpixel;
pub mod template;

use crate::features::{Descriptor, Keypoint};

/// Settings of [`mutual_matches`].
#[derive(Debug, Clone, Copy, PartialEq)]
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
}

impl Default for TemporalConfig {
    fn default() -> Self {
        Self {
            max_distance: 60.0,
            ratio: 0.9,
            max_displacement_px: Some(250.0),
            circular_check: false,
        }
    }
}

/// For each item of `a`, its best match in `b` and the two best distances. With a
/// window, `b` is scanned by column through a sorted index (only the columns within
/// the window).
fn nearest<D: Descriptor>(
    a_kps: &[Keypoint],
    a: &[D],
    b_kps: &[Keypoint],
    b: &[D],
    window: Option<f32>,
) -> Vec<Option<(usize, f32, f32)>> {
    let mut order: Vec<usize> = (0..b.len()).collect();
    order.sort_by(|&i, &j| b_kps[i].x.total_cmp(&b_kps[j].x));
    let xs: Vec<f32> = order.iter().map(|&i| b_kps[i].x).collect();
    a.iter()
        .zip(a_kps)
        .map(|(da, ka)| {
            let (lo, hi) = match window {
                Some(w) => (
                    xs.partition_point(|&x| x < ka.x - w),
                    xs.partition_point(|&x| x <= ka.x + w),
                ),
                None => (0, xs.len()),
            };
            let mut best = (usize::MAX, f32::INFINITY, f32::INFINITY);
            for &j in &order[lo..hi] {
                if let Some(w) = window
                    && (ka.y - b_kps[j].y).abs() > w
                {
                    continue;
                }
                let d = da.distance(&b[j]);
                if d < best.1 {
                    best = (j, d, best.1);
                } else if d < best.2 {
                    best.2 = d;
                }
            }
            (best.0 != usize::MAX).then_some(best)
        })
        .collect()
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
    let ab = nearest(a_kps, a, b_kps, b, config.max_displacement_px);
    let ba = nearest(b_kps, b, a_kps, a, config.max_displacement_px);
    let pass = |m: (usize, f32, f32)| m.1 <= config.max_distance && m.1 < config.ratio * m.2;
    ab.iter()
        .enumerate()
        .filter_map(|(i, m)| {
            let m = (*m)?;
            let back = ba[m.0]?;
            (back.0 == i && pass(m) && pass(back)).then_some((i, m.0))
        })
        .collect()
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
