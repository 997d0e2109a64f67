//! The index of an MCAP file from its summary section: the channels and schemas, the chunk
//! indexes, and each chunk's message index records (log time and offset of every message
//! in the decompressed chunk), read with the `mcap` crate's summary reader. Nothing is
//! decompressed, so opening a zstd or lz4 bag costs no more than a plain one.
//!
//! A file whose summary is missing (a recorder killed mid-write), unreadable, or does not
//! account for every message (no message indexes, messages outside chunks: its statistics
//! count more messages than the indexes hold) is not indexed here: the caller walks its
//! records instead.

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};

use byteorder::{ByteOrder, LittleEndian};
use mcap::Summary;
use mcap::records::Record;
use mcap::sans_io::{SummaryReadEvent, SummaryReader, SummaryReaderOptions};

use super::{Entry, Location, TopicSink};

/// Opcode of a message index record.
const OP_MESSAGE_INDEX: u8 = 0x07;
/// Opcode and length before each record's body.
const RECORD_HEAD: usize = 9;
/// Largest summary record accepted, bytes (a corrupt length must not reserve gigabytes).
const MAX_SUMMARY_RECORD: usize = 1 << 28;

/// The summary of `file` (`size` bytes), or `None` when it has none or it cannot be read.
fn read_summary(file: &mut File, size: u64) -> Option<Summary> {
    let mut reader = SummaryReader::new_with_options(
        SummaryReaderOptions::default()
            .with_file_size(size)
            .with_record_length_limit(MAX_SUMMARY_RECORD),
    );
    while let Some(event) = reader.next_event() {
        match event.ok()? {
            SummaryReadEvent::ReadRequest(n) => {
                let read = file.read(reader.insert(n)).ok()?;
                reader.notify_read(read);
            }
            SummaryReadEvent::SeekRequest(to) => {
                let pos = file.seek(to).ok()?;
                reader.notify_seeked(pos);
            }
        }
    }
    reader.finish()
}

/// The message index records of one chunk: `(channel id, log time, offset)` of each
/// message. `None` when they cannot be read whole.
fn message_indexes(
    file: &mut File,
    size: u64,
    offsets: &BTreeMap<u16, u64>,
    length: u64,
) -> Option<Vec<(u16, u64, u64)>> {
    let Some(&start) = offsets.values().min() else {
        return Some(Vec::new());
    };
    if start.checked_add(length)? > size {
        return None;
    }
    let mut buf = vec![0u8; usize::try_from(length).ok()?];
    file.seek(SeekFrom::Start(start)).ok()?;
    file.read_exact(&mut buf).ok()?;
    let mut out = Vec::new();
    for (&channel, &offset) in offsets {
        let at = usize::try_from(offset - start).ok()?;
        let head = buf.get(at..at.checked_add(RECORD_HEAD)?)?;
        let len = usize::try_from(LittleEndian::read_u64(&head[1..])).ok()?;
        let body_start = at + RECORD_HEAD;
        let body = buf.get(body_start..body_start.checked_add(len)?)?;
        if head[0] != OP_MESSAGE_INDEX {
            return None;
        }
        let Ok(Record::MessageIndex(index)) = mcap::read::parse_record(head[0], body) else {
            return None;
        };
        if index.channel_id != channel {
            return None;
        }
        out.extend(
            index
                .records
                .iter()
                .map(|e| (channel, e.log_time, e.offset)),
        );
    }
    Some(out)
}

/// Indexes `file` (file `file_no` of its bag, `size` bytes) into `sink` from its summary.
/// Returns false, leaving `sink` as it was, when the summary cannot serve (see the module
/// documentation); the file position is then undefined.
///
/// # Errors
/// A one-line message when a channel of the summary clashes with a topic of another file
/// of the bag (another type or encoding).
pub(super) fn index_from_summary(
    file: &mut File,
    size: u64,
    file_no: usize,
    sink: &mut TopicSink,
) -> Result<bool, String> {
    let Some(summary) = read_summary(file, size) else {
        return Ok(false);
    };
    let Some(stats) = &summary.stats else {
        return Ok(false);
    };
    let mut chunks: Vec<_> = summary.chunk_indexes.iter().collect();
    chunks.sort_by_key(|c| c.chunk_start_offset);
    // (channel, log time, chunk offset, offset in the chunk) of every message.
    let mut messages = Vec::new();
    for c in chunks {
        let Some(recs) =
            message_indexes(file, size, &c.message_index_offsets, c.message_index_length)
        else {
            return Ok(false);
        };
        messages.extend(
            recs.into_iter()
                .map(|(ch, t, inner)| (ch, t, c.chunk_start_offset, inner)),
        );
    }
    if messages.len() as u64 != stats.message_count {
        return Ok(false);
    }
    let mut channels: Vec<_> = summary.channels.values().collect();
    channels.sort_by_key(|c| c.id);
    if channels.iter().any(|c| c.schema.is_none())
        || messages
            .iter()
            .any(|m| !summary.channels.contains_key(&m.0))
    {
        return Ok(false);
    }
    let mut topic_of = BTreeMap::new();
    for ch in channels {
        let msg_type = ch.schema.as_ref().map_or("", |s| s.name.as_str());
        topic_of.insert(
            ch.id,
            sink.topic(&ch.topic, msg_type, &ch.message_encoding)?,
        );
    }
    // File order, so that equal log times keep it (as when the records are walked).
    messages.sort_by_key(|m| (m.2, m.3));
    for (channel, log_time, chunk, inner) in messages {
        if let Some(&topic) = topic_of.get(&channel) {
            sink.push(
                topic,
                Entry {
                    log_time_ns: i64::try_from(log_time).unwrap_or(i64::MAX),
                    location: Location::McapChunk {
                        file: file_no,
                        chunk,
                        inner,
                    },
                },
            );
        }
    }
    Ok(true)
}
