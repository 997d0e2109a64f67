//! Left and right images paired by header stamp: each left image with the right image
//! nearest in time, when it is within the tolerance (0: equal stamps) and not taken by
//! a nearer left image. Images without a partner are listed, never dropped silently.

use super::topics_error;
use crate::bag::{Bag, Topic};
use crate::error::RosError;

/// The pairs `(left index, right index)` and the indices left without a partner, of
/// stamp lists (nanoseconds, in any order).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct Pairing {
    /// `(left, right)` indices, in left-stamp order.
    pub pairs: Vec<(usize, usize)>,
    /// Left indices without a right partner.
    pub left_alone: Vec<usize>,
    /// Right indices without a left partner.
    pub right_alone: Vec<usize>,
}

/// An image that found no partner: it is in no frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct UnpairedImage {
    /// Its topic.
    pub topic: String,
    /// 0-based index of the message on its topic.
    pub message: usize,
    /// Its header stamp, nanoseconds.
    pub stamp_ns: i64,
}

impl std::fmt::Display for UnpairedImage {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} message {} (stamp {} ns)",
            self.topic, self.message, self.stamp_ns
        )
    }
}

/// The frames of two image topics paired by header stamp.
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub(crate) struct Paired {
    /// `(first topic's message, second topic's message, first one's stamp ns)` of each
    /// frame, in stamp order.
    pub(crate) frames: Vec<(usize, usize, i64)>,
    /// The images in no frame, in stamp order.
    pub(crate) unpaired: Vec<UnpairedImage>,
    /// The line saying so (when there are any), and where reading stopped (a cut bag).
    pub(crate) notes: Vec<String>,
}

/// The frames of `topics` (each with its header stamps, ns), each image of the first
/// with the nearest of the second within `tolerance_ns`; `sides` name them in messages
/// (`left`, `right`; `colour`, `depth`).
///
/// # Errors
/// [`RosError::Topics`] (listing the bag's topics) when no image finds a partner.
pub(crate) fn pair_frames(
    bag: &Bag,
    topics: [(&Topic, &[i64]); 2],
    sides: [&str; 2],
    tolerance_ns: i64,
) -> Result<Paired, RosError> {
    let [(a, sa), (b, sb)] = topics;
    let tol = tolerance_ns.max(0);
    let p = pair_by_stamp(sa, sb, tol);
    if p.pairs.is_empty() {
        let gap = sa
            .iter()
            .filter_map(|l| sb.iter().map(|r| (r - l).abs()).min())
            .min()
            .map_or("no image on one side".to_owned(), |d| {
                format!("the nearest are {:.3} ms apart", d as f64 * 1e-6)
            });
        return Err(topics_error(
            bag,
            format!(
                "no {} image of {} has a {} image of {} within {:.3} ms of its header stamp ({gap}): \
                 unsynchronised cameras (allow more with the stamp tolerance)",
                sides[0],
                a.name,
                sides[1],
                b.name,
                tol as f64 * 1e-6
            ),
        ));
    }
    let alone = |topic: &Topic, stamps: &[i64], i: usize| UnpairedImage {
        topic: topic.name.clone(),
        message: i,
        stamp_ns: stamps[i],
    };
    let mut unpaired: Vec<UnpairedImage> = p
        .left_alone
        .iter()
        .map(|&i| alone(a, sa, i))
        .chain(p.right_alone.iter().map(|&i| alone(b, sb, i)))
        .collect();
    unpaired.sort_by_key(|u| u.stamp_ns);
    let mut notes = Vec::new();
    if !unpaired.is_empty() {
        notes.push(format!(
            "{} images without a partner within {:.3} ms, not used: {}",
            unpaired.len(),
            tol as f64 * 1e-6,
            unpaired
                .iter()
                .map(ToString::to_string)
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    if let Some(s) = bag.stopped() {
        notes.push(s.to_owned());
    }
    Ok(Paired {
        frames: p.pairs.iter().map(|&(l, r)| (l, r, sa[l])).collect(),
        unpaired,
        notes,
    })
}

/// Pairs `left` and `right` stamps (nanoseconds) within `tolerance_ns`.
#[must_use]
pub fn pair_by_stamp(left: &[i64], right: &[i64], tolerance_ns: i64) -> Pairing {
    let mut lo: Vec<usize> = (0..left.len()).collect();
    lo.sort_by_key(|&i| (left[i], i));
    let mut ro: Vec<usize> = (0..right.len()).collect();
    ro.sort_by_key(|&i| (right[i], i));
    // For each left image, the nearest right image (by sorted position).
    let mut best: Vec<Option<(usize, i64)>> = vec![None; left.len()];
    let mut j = 0usize;
    for &i in &lo {
        while j + 1 < ro.len() && right[ro[j + 1]] <= left[i] {
            j += 1;
        }
        let candidates = [ro.get(j), ro.get(j + 1)];
        best[i] = candidates
            .into_iter()
            .flatten()
            .map(|&r| (r, (right[r] - left[i]).abs()))
            .filter(|&(_, d)| d <= tolerance_ns)
            .min_by_key(|&(r, d)| (d, r));
    }
    // A right image claimed by two left images goes to the nearer (then the earlier).
    let mut owner: Vec<Option<(usize, i64)>> = vec![None; right.len()];
    for &i in &lo {
        if let Some((r, d)) = best[i]
            && owner[r].is_none_or(|(_, od)| d < od)
        {
            owner[r] = Some((i, d));
        }
    }
    let mut out = Pairing::default();
    for &i in &lo {
        match best[i] {
            Some((r, _)) if owner[r].map(|o| o.0) == Some(i) => out.pairs.push((i, r)),
            _ => out.left_alone.push(i),
        }
    }
    out.right_alone = ro.into_iter().filter(|&r| owner[r].is_none()).collect();
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn exact_and_tolerant_pairing() {
        let l = [0, 100, 200, 300];
        let r = [0, 100, 205, 400];
        let p = pair_by_stamp(&l, &r, 0);
        assert_eq!(p.pairs, [(0, 0), (1, 1)]);
        assert_eq!(p.left_alone, [2, 3]);
        assert_eq!(p.right_alone, [2, 3]);
        let p = pair_by_stamp(&l, &r, 10);
        assert_eq!(p.pairs, [(0, 0), (1, 1), (2, 2)]);
        assert_eq!((p.left_alone, p.right_alone), (vec![3], vec![3]));
    }

    #[test]
    fn a_right_image_goes_to_the_nearer_left() {
        let p = pair_by_stamp(&[0, 8], &[6], 10);
        assert_eq!(p.pairs, [(1, 0)]);
        assert_eq!(p.left_alone, [0]);
        let p = pair_by_stamp(&[5, 0], &[10, 0], 0);
        assert_eq!(p.pairs, [(1, 1)]);
        assert!(pair_by_stamp(&[], &[1], 5).pairs.is_empty());
    }
}
