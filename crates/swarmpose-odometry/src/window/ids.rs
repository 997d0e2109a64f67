//! The maps and sets of the window keyed by a track identity or a feature index, hashed
//! by `rustc-hash` (one multiplication per key), not by the standard library's SipHash,
//! under which the maps took 6.6 % of the window's perf samples (issue 34). The keys are
//! the window's own (not an adversary's), and no result depends on the maps' order (the
//! standard one is randomised per process).

use std::collections::{HashMap, HashSet};

use rustc_hash::FxBuildHasher;

/// A map keyed by track identity or feature index.
pub(crate) type IdMap<K, V> = HashMap<K, V, FxBuildHasher>;
/// A set of track identities.
pub(crate) type IdSet<K> = HashSet<K, FxBuildHasher>;

#[cfg(test)]
mod tests {
    use super::*;
    use std::hash::BuildHasher;

    /// Consecutive identities (as the window makes them) spread over the table's index
    /// (low bits) and its tag (top 7 bits); the maps find every key.
    #[test]
    fn consecutive_identities_spread() {
        let build = FxBuildHasher;
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
