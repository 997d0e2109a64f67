//! A compressed MCAP chunk decompressed only as far as a reader needs: the messages asked
//! for lie at known offsets of the decompressed records (the message index), so a scan of
//! header stamps stops right after the last byte it reads. The records after it (most
//! often the data of the chunk's last image) are not decompressed.
//!
//! What is not decompressed is not checked either: the chunk's CRC covers the whole
//! records, so it is checked when a chunk is decompressed whole (reading a frame), not here.

use std::io::Read;

use zstd::stream::raw::Operation;

use byteorder::{ByteOrder, LittleEndian};

use super::mcap_file::{ChunkParts, MAX_CHUNK, MESSAGE_HEAD, OP_MESSAGE, RECORD_HEAD};

/// What decompressing chunks reuses from one to the next: the zstd decoder and the output
/// buffer (a fresh one for each chunk cost more in page faults than the decompression
/// saved).
#[derive(Default)]
pub(crate) struct Scratch {
    zstd: Option<zstd::stream::raw::Decoder<'static>>,
    buf: Vec<u8>,
}

/// The decompressor of a chunk's records.
enum Stream<'a> {
    Zstd,
    Lz4(lz4_flex::frame::FrameDecoder<&'a [u8]>),
}

/// The records of a chunk, decompressed from the start as far as asked.
pub(crate) struct ChunkPrefix<'a> {
    data: &'a [u8],
    /// Bytes of `data` the zstd decoder took.
    read: usize,
    stream: Stream<'a>,
    scratch: &'a mut Scratch,
    /// Bytes of the records decompressed into `scratch.buf`, and how many there are.
    filled: usize,
    size: usize,
    /// The stream ended before what was asked: nothing more comes.
    ended: bool,
}

/// A message asked of a chunk: the offset of its record in the decompressed records, and
/// how many bytes of its data are needed (`None`: all).
pub(crate) type Want = (u64, Option<usize>);

impl<'a> ChunkPrefix<'a> {
    /// The decompressor of the compressed chunk `c` (zstd or lz4, whole), with `scratch`;
    /// `None` for another chunk (uncompressed, cut, too large), read whole instead.
    pub(crate) fn new(c: &ChunkParts<'a>, scratch: &'a mut Scratch) -> Option<Self> {
        if !c.whole || c.uncompressed_size > MAX_CHUNK {
            return None;
        }
        let size = usize::try_from(c.uncompressed_size).ok()?;
        let stream = match c.compression.as_str() {
            "zstd" => {
                match &mut scratch.zstd {
                    Some(d) => d.reinit().ok()?,
                    None => scratch.zstd = Some(zstd::stream::raw::Decoder::new().ok()?),
                }
                Stream::Zstd
            }
            "lz4" => Stream::Lz4(lz4_flex::frame::FrameDecoder::new(c.data)),
            _ => return None,
        };
        if scratch.buf.len() < size {
            scratch.buf.resize(size, 0);
        }
        Some(Self {
            data: c.data,
            read: 0,
            stream,
            scratch,
            filled: 0,
            size,
            ended: false,
        })
    }

    /// The first `n` decompressed bytes, or fewer when the records end before.
    ///
    /// # Errors
    /// A message naming the compression when the stream does not decompress.
    fn upto(&mut self, n: usize) -> Result<&[u8], String> {
        let n = n.min(self.size);
        while self.filled < n && !self.ended {
            let out = &mut self.scratch.buf[self.filled..n];
            let (read, written) = match &mut self.stream {
                Stream::Zstd => {
                    let Some(d) = self.scratch.zstd.as_mut() else {
                        return Err("zstd chunk: no decoder".to_owned());
                    };
                    let st = d
                        .run_on_buffers(&self.data[self.read..], out)
                        .map_err(|e| format!("zstd chunk: {e}"))?;
                    (st.bytes_read, st.bytes_written)
                }
                Stream::Lz4(r) => (0, r.read(out).map_err(|e| format!("lz4 chunk: {e}"))?),
            };
            self.read += read;
            self.filled += written;
            self.ended = read == 0 && written == 0;
        }
        Ok(&self.scratch.buf[..n.min(self.filled)])
    }

    /// The data of the message whose record is at byte `inner` of the records: its first
    /// `head` bytes (all of them when `None` or shorter); `Ok(None)` when there is no
    /// message record there.
    ///
    /// # Errors
    /// As [`ChunkPrefix::upto`].
    pub(crate) fn message(&mut self, (inner, head): Want) -> Result<Option<&[u8]>, String> {
        const HEAD: usize = RECORD_HEAD as usize;
        let Ok(at) = usize::try_from(inner) else {
            return Ok(None);
        };
        let Some(record_end) = at.checked_add(HEAD) else {
            return Ok(None);
        };
        let head_bytes = self.upto(record_end)?;
        if head_bytes.len() < record_end || head_bytes[at] != OP_MESSAGE {
            return Ok(None);
        }
        let Ok(len) = usize::try_from(LittleEndian::read_u64(&head_bytes[at + 1..record_end]))
        else {
            return Ok(None);
        };
        if len < MESSAGE_HEAD {
            return Ok(None);
        }
        let need = head.map_or(len, |h| len.min(MESSAGE_HEAD.saturating_add(h)));
        let Some(end) = record_end.checked_add(need) else {
            return Ok(None);
        };
        let bytes = self.upto(end)?;
        Ok((bytes.len() == end).then(|| &bytes[record_end + MESSAGE_HEAD..end]))
    }

    /// How many bytes were decompressed.
    pub(crate) fn decompressed_bytes(&self) -> usize {
        self.filled
    }
}
