//! The hasher of the window's maps and sets keyed by a track identity or a feature
//! index: one multiplication per key (the multiplicative hash of `rustc-hash`), not the
//! standard library's SipHash, under which the maps took 6.6 % of the window's perf samples
//! (issue 34). The keys are the window's own (not an adversary's), and no result
//! depends on the maps' order (the standard one is randomised per process).

use std::collections::{HashMap, HashSet};
use std::hash::{BuildHasherDefault, Hasher};

/// A map keyed by track identity or feature index.
pub(crate) type IdMap<K, V> = HashMap<K, V, BuildHasherDefault<IdHasher>>;
/// A set of track identities.
pub(crate) type IdSet<K> = HashSet<K, BuildHasherDefault<IdHasher>>;

/// The multiplier of `rustc-hash`'s hash (an odd constant with well-spread bits).
const SEED: u64 = 0xf135_7aea_2e62_a9c5;

/// The hasher of [`IdMap`] and [`IdSet`]: the key times an odd constant (rotated so that
/// the table's index, taken from the low bits, depends on every bit of the key).
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct IdHasher(u64);

impl Hasher for IdHasher {
    #[inline]
    fn finish(&self) -> u64 {
        self.0.rotate_left(26)
    }

    #[inline]
    fn write(&mut self, bytes: &[u8]) {
        for b in bytes {
            self.write_u64(u64::from(*b));
        }
    }

    #[inline]
    fn write_u32(&mut self, i: u32) {
        self.write_u64(u64::from(i));
    }

    #[inline]
    fn write_u64(&mut self, i: u64) {
        self.0 = self.0.wrapping_add(i).wrapping_mul(SEED);
    }

    #[inline]
    fn write_usize(&mut self, i: usize) {
        self.write_u64(i as u64);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    /// Consecutive identities (as the window makes them) spread over the table's index
    /// (low bits) and its tag (top 7 bits); the maps find every key.
    #[test]
    fn consecutive_identities_spread() {
        let build = BuildHasherDefault::<IdHasher>::default();
        let hashes: Vec<u64> = (0..4096u32).map(|t| build.hash_one(t)).collect();
        let low: IdSet<u64> = hashes.iter().map(|h| h & 0xfff).collect();
        let top: IdSet<u64> = hashes.iter().map(|h| h >> 57).collect();
        assert!(low.len() > 1500, "{} of 4096 low parts", low.len());
        assert_eq!(top.len(), 128);
        let mut map = IdMap::default();
        for t in 0..10_000u32 {
            map.insert(t.wrapping_mul(7).wrapping_add(u32::MAX - 3), t);
        }
        assert!((0..10_000u32).all(|t| map[&t.wrapping_mul(7).wrapping_add(u32::MAX - 3)] == t));
        let feature: IdMap<usize, u32> = (0..100).map(|f| (f, f as u32)).collect();
        assert_eq!(feature.get(&42), Some(&42));
    }
}
