//! One MCAP file: indexed from its summary when it has a usable one
//! ([`super::mcap_summary`]: nothing decompressed), else by walking its records from the
//! start (so that a file without summary, or cut short, is read as far as it goes), schema
//! and channel records parsed by the `mcap` crate, chunks decompressed here (zstd, lz4 or
//! none) so that a chunk cut by a dying recorder still gives the messages it holds whole.

use std::borrow::Cow;
use std::fs::File;
use std::io::{Read, Seek, SeekFrom};
use std::path::{Path, PathBuf};
use std::sync::Mutex;

use byteorder::{ByteOrder, LittleEndian};
use mcap::records::Record;

use super::{Entry, Location, TopicSink};
use crate::error::RosError;

/// The 8 bytes at the start (and end) of an MCAP file.
const MAGIC: &[u8; 8] = b"\x89MCAP0\r\n";
/// Opcodes of the records read here.
const OP_SCHEMA: u8 = 0x03;
const OP_CHANNEL: u8 = 0x04;
pub(crate) const OP_MESSAGE: u8 = 0x05;
const OP_CHUNK: u8 = 0x06;
const OP_FOOTER: u8 = 0x02;
const OP_DATA_END: u8 = 0x0F;
/// Opcode and length before each record's body.
pub(crate) const RECORD_HEAD: u64 = 9;
/// Channel, sequence, log time and publish time before a message's data.
pub(crate) const MESSAGE_HEAD: usize = 22;
/// Largest decompressed chunk accepted, bytes (a corrupt size must not reserve gigabytes).
pub(crate) const MAX_CHUNK: u64 = 1 << 28;

/// An indexed MCAP file.
#[derive(Debug)]
pub(crate) struct McapFile {
    pub(crate) path: PathBuf,
    file: Mutex<File>,
}

/// The records of a chunk: `buf[range]` (an uncompressed chunk keeps the record's body as
/// read from the file, not copied).
#[derive(Debug)]
pub(crate) struct ChunkRecords {
    buf: Vec<u8>,
    range: std::ops::Range<usize>,
}

impl ChunkRecords {
    /// Records held in a buffer of their own.
    pub(crate) fn owned(buf: Vec<u8>) -> Self {
        Self {
            range: 0..buf.len(),
            buf,
        }
    }

    fn bytes(&self) -> &[u8] {
        self.buf.get(self.range.clone()).unwrap_or_default()
    }

    /// The bytes it holds in memory.
    pub(crate) fn size_bytes(&self) -> usize {
        self.buf.len()
    }
}

/// Where a chunk's records are: a range of the chunk record's body as read from the file
/// (an uncompressed chunk), or a buffer of their own (decompressed).
enum RecordsAt {
    Body(std::ops::Range<usize>),
    Own(Vec<u8>),
}

/// What indexing needs besides the sink: the channel map of the file.
struct Walk<'a> {
    path: &'a Path,
    file_no: usize,
    sink: &'a mut TopicSink,
    /// Schema id → (name, encoding).
    schemas: Vec<(u16, String, String)>,
    /// Channel id → topic index in the sink.
    channels: Vec<(u16, usize)>,
    messages: usize,
}

pub(crate) fn container(path: &Path, message: impl Into<String>) -> RosError {
    RosError::Container {
        path: path.to_owned(),
        message: message.into(),
    }
}

fn io(path: &Path, source: std::io::Error) -> RosError {
    RosError::Io {
        path: path.to_owned(),
        what: "cannot read the MCAP file",
        source,
    }
}

/// A chunk record's header and its compressed bytes (possibly cut short).
pub(crate) struct ChunkParts<'a> {
    pub(crate) uncompressed_size: u64,
    uncompressed_crc: u32,
    pub(crate) compression: String,
    pub(crate) data: &'a [u8],
    /// Where `data` starts in the record's body.
    data_start: usize,
    /// True when the compressed bytes are all there.
    pub(crate) whole: bool,
}

/// Parses a chunk record's body (of which `body` may be only the first part).
pub(crate) fn chunk_parts(body: &[u8]) -> Option<ChunkParts<'_>> {
    let uncompressed_size = LittleEndian::read_u64(body.get(16..24)?);
    let uncompressed_crc = LittleEndian::read_u32(body.get(24..28)?);
    let clen = LittleEndian::read_u32(body.get(28..32)?) as usize;
    let compression = std::str::from_utf8(body.get(32..32usize.checked_add(clen)?)?).ok()?;
    let at = 32 + clen;
    let size = LittleEndian::read_u64(body.get(at..at + 8)?);
    let rest = body.get(at + 8..)?;
    let whole = size <= rest.len() as u64;
    let data = if whole { &rest[..size as usize] } else { rest };
    Some(ChunkParts {
        uncompressed_size,
        uncompressed_crc,
        compression: compression.to_owned(),
        data,
        data_start: at + 8,
        whole,
    })
}

/// Reads `reader` to its end or its first error (a cut stream), at most `limit` bytes.
fn read_prefix(reader: impl Read, limit: u64) -> Vec<u8> {
    let mut out = Vec::new();
    let mut r = reader.take(limit);
    let mut buf = [0u8; 1 << 16];
    loop {
        match r.read(&mut buf) {
            Ok(0) | Err(_) => return out,
            Ok(n) => out.extend_from_slice(&buf[..n]),
        }
    }
}

/// The records of a chunk, decompressed (an uncompressed chunk's borrowed, not copied); a
/// cut chunk gives what its bytes hold.
fn decompress<'a>(c: &ChunkParts<'a>) -> Result<Cow<'a, [u8]>, String> {
    if c.uncompressed_size > MAX_CHUNK {
        return Err(format!(
            "a chunk of {} bytes decompressed (at most {MAX_CHUNK} accepted)",
            c.uncompressed_size
        ));
    }
    let out = match (c.compression.as_str(), c.whole) {
        ("", _) => return check_records(c, Cow::Borrowed(c.data)),
        ("zstd", true) => zstd::bulk::decompress(c.data, c.uncompressed_size as usize)
            .map_err(|e| format!("zstd chunk: {e}"))?,
        ("zstd", false) => match zstd::stream::read::Decoder::with_buffer(c.data) {
            Ok(d) => read_prefix(d, c.uncompressed_size),
            Err(_) => Vec::new(),
        },
        // The LZ4 frame format (the MCAP specification's `lz4`), decoded in Rust.
        ("lz4", true) => {
            let mut out = Vec::with_capacity(c.uncompressed_size as usize);
            lz4_flex::frame::FrameDecoder::new(c.data)
                .take(c.uncompressed_size)
                .read_to_end(&mut out)
                .map_err(|e| format!("lz4 chunk: {e}"))?;
            out
        }
        ("lz4", false) => read_prefix(
            lz4_flex::frame::FrameDecoder::new(c.data),
            c.uncompressed_size,
        ),
        (other, _) => {
            return Err(format!(
                "chunk compression '{other}' is not zstd, lz4 or none"
            ));
        }
    };
    check_records(c, Cow::Owned(out))
}

/// `out`, the records of chunk `c`, checked against its header's size and CRC when the
/// chunk is whole.
fn check_records<'a>(c: &ChunkParts<'_>, out: Cow<'a, [u8]>) -> Result<Cow<'a, [u8]>, String> {
    if c.whole {
        if out.len() as u64 != c.uncompressed_size {
            return Err(format!(
                "chunk decompresses to {} bytes, its header says {}",
                out.len(),
                c.uncompressed_size
            ));
        }
        if c.uncompressed_crc != 0 && crc32fast::hash(&out) != c.uncompressed_crc {
            return Err("chunk CRC does not match its records (corrupt)".to_owned());
        }
    }
    Ok(out)
}

/// The opcode and body of the record at the start of `buf`; `None` when it is cut.
fn first_record(buf: &[u8]) -> Option<(u8, &[u8])> {
    let head = buf.get(..RECORD_HEAD as usize)?;
    let len = usize::try_from(LittleEndian::read_u64(&head[1..])).ok()?;
    let start = RECORD_HEAD as usize;
    Some((head[0], buf.get(start..start.checked_add(len)?)?))
}

/// A record of a chunk: opcode, body, offset in the decompressed chunk.
type InnerRecord<'a> = (u8, &'a [u8], u64);

/// The `(opcode, body, offset)` of each whole record in `buf`, and whether a record was
/// cut at the end.
fn records(buf: &[u8]) -> (Vec<InnerRecord<'_>>, bool) {
    let mut out = Vec::new();
    let mut pos = 0usize;
    while pos < buf.len() {
        let Some((op, body)) = first_record(&buf[pos..]) else {
            return (out, true);
        };
        out.push((op, body, pos as u64));
        pos += RECORD_HEAD as usize + body.len();
    }
    (out, false)
}

impl Walk<'_> {
    /// Handles one schema, channel or message record (`at`: where a message is).
    fn record(&mut self, op: u8, body: &[u8], at: Location) -> Result<(), String> {
        match op {
            OP_SCHEMA => {
                if let Record::Schema { header, .. } =
                    mcap::read::parse_record(op, body).map_err(|e| format!("schema: {e}"))?
                {
                    self.schemas.retain(|s| s.0 != header.id);
                    self.schemas.push((header.id, header.name, header.encoding));
                }
            }
            OP_CHANNEL => {
                if let Record::Channel(ch) =
                    mcap::read::parse_record(op, body).map_err(|e| format!("channel: {e}"))?
                {
                    let msg_type = self
                        .schemas
                        .iter()
                        .find(|s| s.0 == ch.schema_id)
                        .map(|s| s.1.clone())
                        .ok_or_else(|| {
                            format!(
                                "channel {} names schema {}, not defined before it",
                                ch.topic, ch.schema_id
                            )
                        })?;
                    let topic = self
                        .sink
                        .topic(&ch.topic, &msg_type, &ch.message_encoding)?;
                    self.channels.retain(|c| c.0 != ch.id);
                    self.channels.push((ch.id, topic));
                }
            }
            OP_MESSAGE => {
                let head = body
                    .get(..MESSAGE_HEAD)
                    .ok_or("a message record shorter than its header")?;
                let channel = LittleEndian::read_u16(&head[..2]);
                let log_time = LittleEndian::read_u64(&head[6..14]);
                let topic = self
                    .channels
                    .iter()
                    .find(|c| c.0 == channel)
                    .map(|c| c.1)
                    .ok_or_else(|| {
                        format!("a message on channel {channel}, not defined before it")
                    })?;
                self.sink.push(
                    topic,
                    Entry {
                        log_time_ns: i64::try_from(log_time).unwrap_or(i64::MAX),
                        location: at,
                    },
                );
                self.messages += 1;
            }
            _ => {}
        }
        Ok(())
    }

    /// Indexes the records of the chunk record at `offset`; `Ok(true)` when the chunk was
    /// cut (only then may it end inside a record).
    fn chunk(&mut self, body: &[u8], offset: u64) -> Result<bool, String> {
        let parts = chunk_parts(body).ok_or("a chunk record too short for its header")?;
        let buf = decompress(&parts)?;
        let (recs, cut) = records(&buf);
        if cut && parts.whole {
            return Err("a chunk whose last record is cut (corrupt)".to_owned());
        }
        for (op, rbody, inner) in recs {
            let at = Location::McapChunk {
                file: self.file_no,
                chunk: offset,
                inner,
            };
            self.record(op, rbody, at)?;
        }
        Ok(!parts.whole || cut)
    }
}

impl McapFile {
    /// Indexes the file `path` (file `file_no` of its bag) into `sink`. Returns the file
    /// and, when it ends early (no footer, a record cut), where it stopped.
    ///
    /// # Errors
    /// [`RosError::Container`] naming the byte offset of a malformed record.
    pub(crate) fn index(
        path: &Path,
        file_no: usize,
        sink: &mut TopicSink,
    ) -> Result<(Self, Option<String>), RosError> {
        let mut file = File::open(path).map_err(|e| io(path, e))?;
        let size = file.metadata().map_err(|e| io(path, e))?.len();
        let mut magic = [0u8; 8];
        if size < 8 || file.read_exact(&mut magic).is_err() || &magic != MAGIC {
            return Err(container(
                path,
                format!("not an MCAP file ({size} bytes, no MCAP magic at its start)"),
            ));
        }
        if super::mcap_summary::index_from_summary(&mut file, size, file_no, sink)
            .map_err(|e| container(path, e))?
        {
            return Ok((
                Self {
                    path: path.to_owned(),
                    file: Mutex::new(file),
                },
                None,
            ));
        }
        let mut walk = Walk {
            path,
            file_no,
            sink,
            schemas: Vec::new(),
            channels: Vec::new(),
            messages: 0,
        };
        let stopped = walk_file(&mut walk, &mut file, size)?;
        let stopped = stopped.map(|at| {
            format!(
                "{}: {at}; read up to its last whole message ({} messages)",
                walk.path.display(),
                walk.messages
            )
        });
        Ok((
            Self {
                path: path.to_owned(),
                file: Mutex::new(file),
            },
            stopped,
        ))
    }

    /// `f` of the bytes of the message record at byte `offset` of the file (CDR with its
    /// header; a message outside chunks).
    ///
    /// # Errors
    /// [`RosError::Io`], or [`RosError::Container`] when the record is no longer there.
    pub(crate) fn with_plain_message<R>(
        &self,
        offset: u64,
        f: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, RosError> {
        let (op, body) = self.record_at(offset, false)?;
        (op == OP_MESSAGE)
            .then(|| message_data(&body).map(f))
            .flatten()
            .ok_or_else(|| container(&self.path, format!("no message at byte {offset}")))
    }

    /// `f` of the bytes of the message record at byte `inner` of `records`, the records of
    /// the chunk at byte `chunk`.
    ///
    /// # Errors
    /// [`RosError::Container`] when the record is not there.
    pub(crate) fn with_chunk_message<R>(
        &self,
        records: &ChunkRecords,
        (chunk, inner): (u64, u64),
        f: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, RosError> {
        usize::try_from(inner)
            .ok()
            .and_then(|i| first_record(records.bytes().get(i..)?))
            .filter(|r| r.0 == OP_MESSAGE)
            .and_then(|r| message_data(r.1))
            .map(f)
            .ok_or_else(|| {
                container(
                    &self.path,
                    format!("no message at byte {inner} of the chunk at byte {chunk}"),
                )
            })
    }

    /// The decompressed records of the chunk at `offset` (checked against its size and
    /// CRC when it is whole).
    ///
    /// # Errors
    /// [`RosError::Io`]; [`RosError::Container`] when there is no chunk there or it does
    /// not decompress.
    pub(crate) fn chunk_records(&self, offset: u64) -> Result<ChunkRecords, RosError> {
        self.records_of(offset, self.raw_chunk(offset)?)
    }

    /// The body of the chunk record at `offset`, as in the file (cut short at its end).
    ///
    /// # Errors
    /// [`RosError::Io`]; [`RosError::Container`] when there is no chunk there.
    pub(crate) fn raw_chunk(&self, offset: u64) -> Result<Vec<u8>, RosError> {
        let (op, body) = self.record_at(offset, true)?;
        if op != OP_CHUNK {
            return Err(container(&self.path, format!("no chunk at byte {offset}")));
        }
        Ok(body)
    }

    /// The records of `body`, the chunk record at `offset`, decompressed whole.
    ///
    /// # Errors
    /// [`RosError::Container`] when it does not decompress or its size or CRC is wrong.
    pub(crate) fn records_of(&self, offset: u64, body: Vec<u8>) -> Result<ChunkRecords, RosError> {
        let bad = |e: String| container(&self.path, format!("chunk at byte {offset}: {e}"));
        let parts = chunk_parts(&body).ok_or_else(|| bad("too short".to_owned()))?;
        let start = parts.data_start;
        // Where the records are, decided before `body` (which `parts` borrows) moves.
        let place = match decompress(&parts).map_err(bad)? {
            Cow::Borrowed(b) => RecordsAt::Body(start..start + b.len()),
            Cow::Owned(v) => RecordsAt::Own(v),
        };
        Ok(match place {
            RecordsAt::Own(buf) => ChunkRecords::owned(buf),
            RecordsAt::Body(range) => ChunkRecords { buf: body, range },
        })
    }

    /// The opcode and body of the record at `offset` (cut short at the end of the file
    /// when `allow_cut`).
    fn record_at(&self, offset: u64, allow_cut: bool) -> Result<(u8, Vec<u8>), RosError> {
        let mut f = self
            .file
            .lock()
            .map_err(|_| container(&self.path, "file handle poisoned"))?;
        let size = f.metadata().map_err(|e| io(&self.path, e))?.len();
        let mut head = [0u8; RECORD_HEAD as usize];
        f.seek(SeekFrom::Start(offset))
            .and_then(|_| f.read_exact(&mut head))
            .map_err(|e| io(&self.path, e))?;
        let len = LittleEndian::read_u64(&head[1..]);
        let avail = size.saturating_sub(offset + RECORD_HEAD);
        if len > avail && !allow_cut {
            return Err(container(
                &self.path,
                format!("record at byte {offset} is cut"),
            ));
        }
        let mut body = vec![0u8; len.min(avail) as usize];
        f.read_exact(&mut body).map_err(|e| io(&self.path, e))?;
        Ok((head[0], body))
    }
}

/// The data of a message record's body.
fn message_data(body: &[u8]) -> Option<&[u8]> {
    body.get(MESSAGE_HEAD..)
}

/// Walks the top-level records of `file` (after the magic) until the footer, the data
/// end or the end of the file. Returns where it stopped when that was not a proper end.
fn walk_file(walk: &mut Walk<'_>, file: &mut File, size: u64) -> Result<Option<String>, RosError> {
    let path = walk.path;
    let mut pos = 8u64;
    let mut head = [0u8; RECORD_HEAD as usize];
    loop {
        if pos == size {
            return Ok(Some(format!(
                "ends at byte {size} without its summary (no footer)"
            )));
        }
        if size - pos < RECORD_HEAD {
            return Ok(Some(format!(
                "cut at byte {size}, inside the record at byte {pos}"
            )));
        }
        file.seek(SeekFrom::Start(pos))
            .and_then(|_| file.read_exact(&mut head))
            .map_err(|e| io(path, e))?;
        let (op, len) = (head[0], LittleEndian::read_u64(&head[1..]));
        if op == OP_FOOTER || op == OP_DATA_END {
            return Ok(None);
        }
        let avail = size - pos - RECORD_HEAD;
        let cut = len > avail;
        if cut && op != OP_CHUNK {
            return Ok(Some(format!(
                "cut at byte {size}, inside a record of {len} bytes at byte {pos}"
            )));
        }
        if matches!(op, OP_SCHEMA | OP_CHANNEL | OP_MESSAGE | OP_CHUNK) {
            let mut body = vec![0u8; len.min(avail) as usize];
            file.read_exact(&mut body).map_err(|e| io(path, e))?;
            let at = |e: String| container(path, format!("record at byte {pos}: {e}"));
            if op == OP_CHUNK {
                if walk.chunk(&body, pos).map_err(at)? || cut {
                    return Ok(Some(format!(
                        "cut at byte {size}, inside the chunk at byte {pos}"
                    )));
                }
            } else {
                let loc = Location::McapPlain {
                    file: walk.file_no,
                    offset: pos,
                };
                walk.record(op, &body, loc).map_err(at)?;
            }
        }
        pos += RECORD_HEAD + len;
    }
}
