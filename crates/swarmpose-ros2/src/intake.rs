//! Left and right images paired by exact header stamp (as `message_filters`'
//! `ExactTime`), keeping only the newest pair the engine has not taken: a robot needs a
//! fresh pose, not a queue. Pure bookkeeping (no DDS, no engine), counted so that the
//! node can report what it dropped and why.
//!
//! - An image waits for its partner in a queue of at most [`MAX_WAITING`] per side;
//!   when its partner arrives, the pair becomes the pending pair, and every image older
//!   than it on either side is given up (`unpaired`: its partner never came).
//! - A new pair that replaces a pending pair the engine had not taken yet counts as one
//!   `dropped` pair.
//! - A pair no newer than the last pair taken is refused (`out_of_order`).

use std::collections::VecDeque;
use std::time::Instant;

use swarmpose_ros::msg::{CameraInfo, Image};

/// Most images of one side waiting for their partner.
pub const MAX_WAITING: usize = 16;

/// A left and a right image with the same header stamp.
#[derive(Debug, Clone)]
pub struct Pair {
    /// The left image.
    pub left: Image,
    /// The right image.
    pub right: Image,
    /// Their header stamp, nanoseconds.
    pub stamp_ns: i64,
    /// When the pair was complete (its second image taken from DDS).
    pub complete: Instant,
}

/// What happened to the images so far.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Left images received.
    pub left: u64,
    /// Right images received.
    pub right: u64,
    /// Pairs formed.
    pub pairs: u64,
    /// Pairs replaced by a newer one before the engine took them.
    pub dropped: u64,
    /// Left images given up without a right image of the same stamp.
    pub unpaired_left: u64,
    /// Right images given up without a left image of the same stamp.
    pub unpaired_right: u64,
    /// Pairs no newer than the last pair taken.
    pub out_of_order: u64,
    /// Samples that did not decode as their type.
    pub undecodable: u64,
    /// Pairs refused by the checks before the engine (bad input).
    pub refused: u64,
}

/// The pairing state: waiting images, the newest camera_info of each side, the pending
/// pair.
#[derive(Debug, Default)]
pub struct Intake {
    left: VecDeque<Image>,
    right: VecDeque<Image>,
    /// The newest `camera_info` of the left and right camera.
    pub left_info: Option<CameraInfo>,
    /// See `left_info`.
    pub right_info: Option<CameraInfo>,
    pending: Option<Pair>,
    last_taken_ns: Option<i64>,
    /// The counts.
    pub counts: Counts,
    /// The last sample that did not decode: the topic and why.
    pub decode_error: Option<String>,
}

fn stamp_ns(img: &Image) -> i64 {
    img.header.stamp.as_nanos()
}

/// Which camera an image comes from.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The left camera.
    Left,
    /// The right camera.
    Right,
}

impl Intake {
    /// Takes an image of `side` received at `now`; returns whether it completed a pair.
    pub fn push(&mut self, side: Side, img: Image, now: Instant) -> bool {
        let (mine, theirs) = match side {
            Side::Left => {
                self.counts.left += 1;
                (&mut self.left, &mut self.right)
            }
            Side::Right => {
                self.counts.right += 1;
                (&mut self.right, &mut self.left)
            }
        };
        let stamp = stamp_ns(&img);
        let Some(k) = theirs.iter().position(|o| stamp_ns(o) == stamp) else {
            mine.push_back(img);
            if mine.len() > MAX_WAITING {
                mine.pop_front();
                self.count_unpaired(side, 1);
            }
            return false;
        };
        let Some(partner) = theirs.remove(k) else {
            return false;
        };
        let (left, right) = match side {
            Side::Left => (img, partner),
            Side::Right => (partner, img),
        };
        self.give_up_older_than(stamp);
        if self.last_taken_ns.is_some_and(|t| stamp <= t) {
            self.counts.out_of_order += 1;
            return false;
        }
        self.counts.pairs += 1;
        if self.pending.is_some() {
            self.counts.dropped += 1;
        }
        self.pending = Some(Pair {
            left,
            right,
            stamp_ns: stamp,
            complete: now,
        });
        true
    }

    fn count_unpaired(&mut self, side: Side, n: u64) {
        match side {
            Side::Left => self.counts.unpaired_left += n,
            Side::Right => self.counts.unpaired_right += n,
        }
    }

    /// Gives up the waiting images older than `stamp`: their partners would have come
    /// before this pair's.
    fn give_up_older_than(&mut self, stamp: i64) {
        for side in [Side::Left, Side::Right] {
            let q = match side {
                Side::Left => &mut self.left,
                Side::Right => &mut self.right,
            };
            let before = q.len();
            q.retain(|i| stamp_ns(i) > stamp);
            let n = (before - q.len()) as u64;
            self.count_unpaired(side, n);
        }
    }

    /// Takes the pending pair, if any.
    pub fn take(&mut self) -> Option<Pair> {
        let p = self.pending.take()?;
        self.last_taken_ns = Some(p.stamp_ns);
        Some(p)
    }

    /// Images waiting for their partner: (left, right).
    #[must_use]
    pub fn waiting(&self) -> (usize, usize) {
        (self.left.len(), self.right.len())
    }

    /// The stamps of the newest waiting image of each side, nanoseconds.
    #[must_use]
    pub fn newest_waiting_ns(&self) -> (Option<i64>, Option<i64>) {
        (
            self.left.back().map(stamp_ns),
            self.right.back().map(stamp_ns),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use swarmpose_ros::msg::{Header, Time};

    fn img(ns: i64) -> Image {
        Image {
            header: Header {
                stamp: Time::from_nanos(ns),
                frame_id: String::new(),
            },
            height: 1,
            width: 1,
            encoding: "mono8".into(),
            is_bigendian: 0,
            step: 1,
            data: vec![0],
        }
    }

    #[test]
    fn pairs_by_exact_stamp_and_keeps_the_newest() {
        let mut i = Intake::default();
        assert!(!i.push(Side::Left, img(10), Instant::now()));
        assert!(i.push(Side::Right, img(10), Instant::now()));
        // A second pair before the engine took the first: the first is dropped.
        assert!(!i.push(Side::Right, img(20), Instant::now()));
        assert!(i.push(Side::Left, img(20), Instant::now()));
        assert_eq!(i.counts.dropped, 1);
        let p = i.take().expect("a pair");
        assert_eq!(p.stamp_ns, 20);
        assert!(i.take().is_none());
        // An older pair after it is refused.
        i.push(Side::Left, img(15), Instant::now());
        assert!(!i.push(Side::Right, img(15), Instant::now()));
        assert_eq!(i.counts.out_of_order, 1);
    }

    #[test]
    fn images_without_partner_are_given_up_and_counted() {
        let mut i = Intake::default();
        i.push(Side::Left, img(1), Instant::now());
        i.push(Side::Left, img(2), Instant::now());
        i.push(Side::Right, img(3), Instant::now()); // no left 3 yet
        assert!(!i.push(Side::Right, img(4), Instant::now()));
        assert!(i.push(Side::Left, img(4), Instant::now()));
        assert_eq!(i.counts.unpaired_left, 2);
        assert_eq!(i.counts.unpaired_right, 1);
        assert_eq!(i.waiting(), (0, 0));
        // A right camera that never sends: the left queue stays bounded.
        for k in 10..10 + MAX_WAITING as i64 + 5 {
            i.push(Side::Left, img(k), Instant::now());
        }
        assert_eq!(i.waiting().0, MAX_WAITING);
        assert_eq!(i.counts.unpaired_left, 2 + 5);
    }
}
