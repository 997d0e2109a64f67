//! The decompressed MCAP chunks a bag keeps between reads, bounded in bytes.
//!
//! Opening a camera input reads every image's header ([`super::Bag::visit`], in file
//! order), and a run then reads the frames in the same order: the chunks decompressed
//! first are kept while they fit in the budget, so that a bag shorter than the budget is
//! decompressed once, not twice (a longer one saves the budget's worth). Besides them, the
//! last chunk decompressed is always kept: the messages of one chunk are read one after
//! the other.

use std::sync::Arc;

use super::mcap_file::ChunkRecords;

/// Default budget of a bag's kept chunks, bytes of decompressed records (some 70 stereo
/// frames of 1241 x 376 mono8 images).
pub const DEFAULT_CHUNK_CACHE_BYTES: usize = 64 << 20;

/// A chunk: the index of its file in the bag and the byte offset of its record.
pub(crate) type ChunkKey = (usize, u64);

/// The chunks kept: the first ones decompressed (within the budget), and the last one.
#[derive(Debug)]
pub(crate) struct ChunkCache {
    budget_bytes: usize,
    kept_bytes: usize,
    kept: Vec<(ChunkKey, Arc<ChunkRecords>)>,
    last: Option<(ChunkKey, Arc<ChunkRecords>)>,
}

impl ChunkCache {
    /// An empty cache that keeps at most `budget_bytes` besides the last chunk.
    pub(crate) fn new(budget_bytes: usize) -> Self {
        Self {
            budget_bytes,
            kept_bytes: 0,
            kept: Vec::new(),
            last: None,
        }
    }

    /// The records of chunk `key`, when kept.
    pub(crate) fn get(&self, key: ChunkKey) -> Option<Arc<ChunkRecords>> {
        self.last
            .iter()
            .chain(&self.kept)
            .find(|(k, _)| *k == key)
            .map(|(_, r)| Arc::clone(r))
    }

    /// Keeps `records` of chunk `key`: as the last chunk, and among the kept ones while
    /// they fit in the budget.
    pub(crate) fn put(&mut self, key: ChunkKey, records: Arc<ChunkRecords>) {
        let size = records.size_bytes();
        if self.kept_bytes + size <= self.budget_bytes && self.kept.iter().all(|(k, _)| *k != key) {
            self.kept_bytes += size;
            self.kept.push((key, Arc::clone(&records)));
        }
        self.last = Some((key, records));
    }

    /// Whether a chunk of `size_bytes` would be kept besides the last one.
    pub(crate) fn has_room(&self, size_bytes: u64) -> bool {
        usize::try_from(size_bytes)
            .is_ok_and(|size| self.kept_bytes.saturating_add(size) <= self.budget_bytes)
    }

    /// Sets the budget, dropping the chunks kept last until the others fit in it.
    pub(crate) fn set_budget(&mut self, budget_bytes: usize) {
        self.budget_bytes = budget_bytes;
        while self.kept_bytes > budget_bytes {
            let Some((_, r)) = self.kept.pop() else {
                break;
            };
            self.kept_bytes -= r.size_bytes();
        }
    }

    /// The bytes of the chunks kept within the budget (the last one not counted).
    pub(crate) fn kept_bytes(&self) -> usize {
        self.kept_bytes
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn records(n: usize) -> Arc<ChunkRecords> {
        Arc::new(ChunkRecords::owned(vec![7; n]))
    }

    #[test]
    fn the_first_chunks_are_kept_within_the_budget_and_the_last_always() {
        let mut c = ChunkCache::new(250);
        for offset in 0..5 {
            c.put((0, offset), records(100));
        }
        assert_eq!(c.kept_bytes(), 200);
        assert!(c.has_room(50) && !c.has_room(51));
        let kept: Vec<bool> = (0..5).map(|o| c.get((0, o)).is_some()).collect();
        assert_eq!(kept, [true, true, false, false, true]);
        assert!(c.get((1, 0)).is_none(), "another file's chunk");
        // The same chunk again is not counted twice.
        c.put((0, 1), records(100));
        assert_eq!(c.kept_bytes(), 200);
        c.set_budget(150);
        assert_eq!(c.kept_bytes(), 100);
        assert!(
            c.get((0, 0)).is_some() && c.get((0, 1)).is_some(),
            "0 kept, 1 last"
        );
        c.set_budget(0);
        c.put((0, 3), records(100));
        assert_eq!(c.kept_bytes(), 0);
        let kept: Vec<bool> = (0..5).map(|o| c.get((0, o)).is_some()).collect();
        assert_eq!(kept, [false, false, false, true, false]);
    }
}
