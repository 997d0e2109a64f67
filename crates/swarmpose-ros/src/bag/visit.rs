//! Reading every message of a few topics in file order ([`Bag::visit`]), or only their
//! first bytes ([`Bag::visit_heads`]: the header stamps of images, when a camera input is
//! opened). A compressed chunk is decompressed once for all its messages; when it is not
//! kept for later reads ([`super::chunk_cache`]: a bag longer than the budget), only as
//! far as the last byte needed ([`super::chunk_prefix`]).

use std::sync::{Arc, PoisonError};

use super::chunk_cache::ChunkKey;
use super::chunk_prefix::{ChunkPrefix, Scratch};
use super::mcap_file::{McapFile, chunk_parts, container};
use super::{Bag, Location, Storage, Topic};
use crate::error::RosError;

/// A message to visit: where it is, its topic's index among the visited ones, and its
/// index on the topic.
type Visit = (Location, usize, usize);

/// Whether `a` and `b` are in the same MCAP chunk.
fn same_chunk(a: Location, b: Location) -> bool {
    matches!(
        (a, b),
        (
            Location::McapChunk { file: fa, chunk: ca, .. },
            Location::McapChunk { file: fb, chunk: cb, .. },
        ) if fa == fb && ca == cb
    )
}

/// Visits `group`, messages of the chunk at byte `offset` of file `m`, from `prefix`:
/// of a message of topic `k`, its first `head(k)` bytes.
fn visit_prefix(
    m: &McapFile,
    offset: u64,
    prefix: &mut ChunkPrefix<'_>,
    group: &[Visit],
    head: &impl Fn(usize) -> Option<usize>,
    f: &mut impl FnMut(usize, usize, &[u8]) -> Result<(), RosError>,
) -> Result<(), RosError> {
    for &(location, k, i) in group {
        let Location::McapChunk { inner, .. } = location else {
            continue;
        };
        let bytes = prefix
            .message((inner, head(k)))
            .map_err(|e| container(&m.path, format!("chunk at byte {offset}: {e}")))?
            .ok_or_else(|| {
                container(
                    &m.path,
                    format!("no message at byte {inner} of the chunk at byte {offset}"),
                )
            })?;
        f(k, i, bytes)?;
    }
    Ok(())
}

impl Bag {
    /// Calls `f(k, i, bytes)` for every message `i` of each topic `topics[k]`, in the
    /// order of the files (each chunk read and decompressed once, whatever the topics'
    /// order): the way to read every message of a few topics.
    ///
    /// # Errors
    /// As [`Bag::read`], and the first error of `f` (which stops the visit).
    pub fn visit(
        &self,
        topics: &[&Topic],
        f: impl FnMut(usize, usize, &[u8]) -> Result<(), RosError>,
    ) -> Result<(), RosError> {
        self.visit_heads(topics, &[], f).map(|_| ())
    }

    /// As [`Bag::visit`], when only the first `heads[k]` bytes of each message of
    /// `topics[k]` are needed (`None`, or no entry: all of them): `f` is given at least
    /// these (the whole message when it is shorter, and sometimes when it is not). A
    /// compressed chunk that is not kept for later reads is decompressed only up to the
    /// last byte needed. Returns how many bytes of decompressed records were not
    /// decompressed.
    ///
    /// # Errors
    /// As [`Bag::visit`].
    pub fn visit_heads(
        &self,
        topics: &[&Topic],
        heads: &[Option<usize>],
        mut f: impl FnMut(usize, usize, &[u8]) -> Result<(), RosError>,
    ) -> Result<u64, RosError> {
        let mut all: Vec<Visit> = topics
            .iter()
            .enumerate()
            .flat_map(|(k, t)| {
                t.entries
                    .iter()
                    .enumerate()
                    .map(move |(i, e)| (e.location, k, i))
            })
            .collect();
        all.sort_by_key(|m| m.0.file_order());
        let head = |k: usize| heads.get(k).copied().flatten();
        let mut skipped = 0u64;
        let mut scratch = Scratch::default();
        let mut rest = &all[..];
        while let Some(&(location, ..)) = rest.first() {
            let n = rest
                .iter()
                .take_while(|m| same_chunk(m.0, location))
                .count()
                .max(1);
            let (group, tail) = rest.split_at(n);
            rest = tail;
            if let Location::McapChunk { file, chunk, .. } = location
                && let Some(Storage::Mcap(m)) = self.files.get(file)
                && group.iter().any(|v| head(v.1).is_some())
            {
                skipped +=
                    self.visit_chunk(m, (file, chunk), group, (&head, &mut scratch), &mut f)?;
            } else {
                for &(location, k, i) in group {
                    self.with_bytes(location, |b| f(k, i, b))??;
                }
            }
        }
        Ok(skipped)
    }

    /// Visits `group`, messages of chunk `key` of file `m`: from the kept records, or
    /// decompressed whole when the cache has room for them, else decompressed as far as
    /// needed. Returns the bytes not decompressed.
    fn visit_chunk(
        &self,
        m: &McapFile,
        key: ChunkKey,
        group: &[Visit],
        (head, scratch): (&impl Fn(usize) -> Option<usize>, &mut Scratch),
        f: &mut impl FnMut(usize, usize, &[u8]) -> Result<(), RosError>,
    ) -> Result<u64, RosError> {
        let cache = || self.chunks.lock().unwrap_or_else(PoisonError::into_inner);
        let offset = key.1;
        let bad = |e: String| container(&m.path, format!("chunk at byte {offset}: {e}"));
        let kept = cache().get(key);
        let records = match kept {
            Some(records) => records,
            None => {
                let body = m.raw_chunk(offset)?;
                {
                    let parts = chunk_parts(&body).ok_or_else(|| bad("too short".to_owned()))?;
                    if !cache().has_room(parts.uncompressed_size)
                        && let Some(mut prefix) = ChunkPrefix::new(&parts, scratch)
                    {
                        visit_prefix(m, offset, &mut prefix, group, head, f)?;
                        let done = prefix.decompressed_bytes() as u64;
                        return Ok(parts.uncompressed_size.saturating_sub(done));
                    }
                }
                let records = Arc::new(m.records_of(offset, body)?);
                cache().put(key, Arc::clone(&records));
                records
            }
        };
        for &(location, k, i) in group {
            if let Location::McapChunk { inner, .. } = location {
                m.with_chunk_message(&records, (offset, inner), |b| f(k, i, b))??;
            }
        }
        Ok(0)
    }
}
