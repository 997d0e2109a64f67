//! ROS 2 bags without ROS: a single `.mcap` file, a single SQLite `.db3` file, or a
//! rosbag2 folder (`metadata.yaml` naming one or more `.mcap` or `.db3` files: a split
//! bag). [`Bag::open`] indexes the messages of every file by topic (topic, type, log time
//! and where the bytes are: from an MCAP file's summary, or its records when it has none;
//! from a `.db3` file's `messages` table), and [`Bag::read`] fetches one message's bytes
//! afterwards, so that a stereo sequence has random access to its frames;
//! [`Bag::visit`] reads many messages in file order, each chunk decompressed once.
//! Decompressed chunks are kept within a budget of bytes ([`DEFAULT_CHUNK_CACHE_BYTES`],
//! [`Bag::set_chunk_cache_bytes`]), so that a short bag whose headers were read at opening
//! is not decompressed again frame by frame.
//!
//! An MCAP file whose recorder died has no summary and may end in the middle of a record
//! (even of a compressed chunk): it is read up to its last whole message and
//! [`Bag::stopped`] says where it stopped.

mod chunk_cache;
mod chunk_prefix;
mod mcap_file;
mod mcap_summary;
mod metadata;
mod sqlite;
mod visit;

use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex, PoisonError};

use crate::error::RosError;
use crate::msg::{RosMessage, decode};

pub use chunk_cache::DEFAULT_CHUNK_CACHE_BYTES;
pub use metadata::{Metadata, parse_metadata};

use chunk_cache::{ChunkCache, ChunkKey};
use mcap_file::{ChunkRecords, McapFile};

/// Where a message's bytes are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Location {
    /// An MCAP message record outside chunks, at this byte of file `file`.
    McapPlain {
        /// Index of the file in the bag.
        file: usize,
        /// Byte offset of the record's opcode.
        offset: u64,
    },
    /// An MCAP message record inside the chunk record at byte `chunk` of `file`, at byte
    /// `inner` of the decompressed chunk.
    McapChunk {
        /// Index of the file in the bag.
        file: usize,
        /// Byte offset of the chunk record's opcode.
        chunk: u64,
        /// Byte offset of the message record in the decompressed records.
        inner: u64,
    },
    /// A row of the `messages` table of SQLite file `file`.
    Sqlite {
        /// Index of the file in the bag.
        file: usize,
        /// The row's `id`.
        id: i64,
    },
}

impl Location {
    /// The file and the position in it: sorting by it reads a file front to back, the
    /// messages of a chunk together.
    fn file_order(self) -> (usize, u64, u64) {
        match self {
            Self::McapPlain { file, offset } => (file, offset, 0),
            Self::McapChunk { file, chunk, inner } => (file, chunk, inner),
            Self::Sqlite { file, id } => (file, id as u64, 0),
        }
    }

    fn file(self) -> usize {
        self.file_order().0
    }
}

/// One message of a topic: its log (receive) time and where its bytes are.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Entry {
    /// Log time, nanoseconds (the recorder's receive time; not the header stamp).
    pub log_time_ns: i64,
    pub(crate) location: Location,
}

/// A topic of a bag: name, type, and its messages in log-time order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Topic {
    /// Topic name (`/camera/left/image_raw`).
    pub name: String,
    /// Message type, `pkg/msg/Name`.
    pub msg_type: String,
    /// Serialisation (`cdr` for ROS 2).
    pub encoding: String,
    /// The messages, in log-time order (ties in file order).
    pub entries: Vec<Entry>,
}

/// The storage of one file of a bag.
#[derive(Debug)]
enum Storage {
    Mcap(McapFile),
    Sqlite(sqlite::SqliteFile),
}

/// An indexed ROS 2 bag.
#[derive(Debug)]
pub struct Bag {
    path: PathBuf,
    files: Vec<Storage>,
    topics: Vec<Topic>,
    stopped: Option<String>,
    /// Decompressed MCAP chunks kept between reads.
    chunks: Mutex<ChunkCache>,
}

/// Collects topics and their messages while the files are indexed.
#[derive(Debug, Default)]
pub(crate) struct TopicSink {
    topics: Vec<Topic>,
}

impl TopicSink {
    /// The index of topic `name`, added when new.
    ///
    /// # Errors
    /// A message naming the topic when it was seen with another type or encoding.
    pub(crate) fn topic(
        &mut self,
        name: &str,
        msg_type: &str,
        encoding: &str,
    ) -> Result<usize, String> {
        if let Some(i) = self.topics.iter().position(|t| t.name == name) {
            let t = &self.topics[i];
            if t.msg_type != msg_type || t.encoding != encoding {
                return Err(format!(
                    "topic {name} is {msg_type} ({encoding}) here but {} ({}) before",
                    t.msg_type, t.encoding
                ));
            }
            return Ok(i);
        }
        self.topics.push(Topic {
            name: name.to_owned(),
            msg_type: msg_type.to_owned(),
            encoding: encoding.to_owned(),
            entries: Vec::new(),
        });
        Ok(self.topics.len() - 1)
    }

    /// Adds a message to topic `topic` (an index from [`TopicSink::topic`]).
    pub(crate) fn push(&mut self, topic: usize, entry: Entry) {
        if let Some(t) = self.topics.get_mut(topic) {
            t.entries.push(entry);
        }
    }
}

impl Bag {
    /// Opens and indexes a bag: an `.mcap` file, a `.db3` file, or a folder with
    /// `metadata.yaml`.
    ///
    /// # Errors
    /// [`RosError::NotABag`] for any other path; [`RosError::Io`] or
    /// [`RosError::Container`] naming the file for an unreadable or malformed one
    /// (including a `metadata.yaml` naming a missing file and an empty file).
    pub fn open(path: &Path) -> Result<Self, RosError> {
        let files: Vec<PathBuf> = if path.is_dir() {
            let meta = path.join("metadata.yaml");
            if !meta.is_file() {
                return Err(RosError::NotABag {
                    path: path.to_owned(),
                });
            }
            metadata::read_metadata(&meta)?
                .files
                .iter()
                .map(|f| path.join(f))
                .collect()
        } else if path.is_file() {
            vec![path.to_owned()]
        } else {
            return Err(RosError::Io {
                path: path.to_owned(),
                what: "cannot open the bag",
                source: std::io::Error::from(std::io::ErrorKind::NotFound),
            });
        };
        let mut sink = TopicSink::default();
        let mut storages = Vec::new();
        let mut stopped = None;
        for (k, f) in files.iter().enumerate() {
            if !f.is_file() {
                return Err(RosError::Container {
                    path: path.join("metadata.yaml"),
                    message: format!("names {}, which does not exist", f.display()),
                });
            }
            match f.extension().and_then(|e| e.to_str()) {
                Some("mcap") => {
                    let (file, stop) = McapFile::index(f, k, &mut sink)?;
                    storages.push(Storage::Mcap(file));
                    if stopped.is_none() {
                        stopped = stop;
                    }
                }
                Some("db3") => {
                    storages.push(Storage::Sqlite(sqlite::SqliteFile::index(f, k, &mut sink)?))
                }
                _ => {
                    return Err(RosError::NotABag { path: f.clone() });
                }
            }
        }
        let mut topics = sink.topics;
        for t in &mut topics {
            t.entries.sort_by_key(|e| e.log_time_ns);
        }
        Ok(Self {
            path: path.to_owned(),
            files: storages,
            topics,
            stopped,
            chunks: Mutex::new(ChunkCache::new(DEFAULT_CHUNK_CACHE_BYTES)),
        })
    }

    /// Sets the budget of decompressed MCAP chunks kept between reads, bytes
    /// ([`DEFAULT_CHUNK_CACHE_BYTES`] when opened; 0 keeps only the last chunk read).
    pub fn set_chunk_cache_bytes(&mut self, bytes: usize) {
        self.chunks
            .get_mut()
            .unwrap_or_else(PoisonError::into_inner)
            .set_budget(bytes);
    }

    /// The bytes of decompressed MCAP chunks kept within the budget.
    #[must_use]
    pub fn chunk_cache_bytes(&self) -> usize {
        self.chunks
            .lock()
            .unwrap_or_else(PoisonError::into_inner)
            .kept_bytes()
    }

    /// The bag's path as given.
    #[must_use]
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// The topics, in the order first seen.
    #[must_use]
    pub fn topics(&self) -> &[Topic] {
        &self.topics
    }

    /// The topic named `name`.
    #[must_use]
    pub fn topic(&self, name: &str) -> Option<&Topic> {
        self.topics.iter().find(|t| t.name == name)
    }

    /// Where reading stopped early (a cut MCAP file), in one line; `None` when every file
    /// was read to its end.
    #[must_use]
    pub fn stopped(&self) -> Option<&str> {
        self.stopped.as_deref()
    }

    /// The topics as one line each: `name (type, N messages)`.
    #[must_use]
    pub fn listing(&self) -> String {
        if self.topics.is_empty() {
            return "the bag has no topics".to_owned();
        }
        let items: Vec<String> = self
            .topics
            .iter()
            .map(|t| format!("{} ({}, {})", t.name, t.msg_type, t.entries.len()))
            .collect();
        format!("topics: {}", items.join("; "))
    }

    /// The serialised bytes of message `index` of `topic` (CDR with its header).
    ///
    /// # Errors
    /// [`RosError::Container`] for an index out of range or bytes that cannot be read
    /// again; [`RosError::Io`].
    pub fn read(&self, topic: &Topic, index: usize) -> Result<Vec<u8>, RosError> {
        self.with_message(topic, index, <[u8]>::to_vec)
    }

    /// `f` of the bytes of message `index` of `topic`, borrowed where they are (a chunk's
    /// records), not copied.
    ///
    /// # Errors
    /// As [`Bag::read`].
    fn with_message<R>(
        &self,
        topic: &Topic,
        index: usize,
        f: impl FnOnce(&[u8]) -> R,
    ) -> Result<R, RosError> {
        let entry = topic
            .entries
            .get(index)
            .ok_or_else(|| RosError::Container {
                path: self.path.clone(),
                message: format!(
                    "topic {}: message {index} out of range ({} messages)",
                    topic.name,
                    topic.entries.len()
                ),
            })?;
        self.with_bytes(entry.location, f)
    }

    /// `f` of the bytes at `location`.
    fn with_bytes<R>(&self, location: Location, f: impl FnOnce(&[u8]) -> R) -> Result<R, RosError> {
        match (self.files.get(location.file()), location) {
            (Some(Storage::Mcap(m)), Location::McapChunk { file, chunk, inner }) => {
                let records = self.chunk(m, (file, chunk))?;
                m.with_chunk_message(&records, (chunk, inner), f)
            }
            (Some(Storage::Mcap(m)), Location::McapPlain { offset, .. }) => {
                m.with_plain_message(offset, f)
            }
            (Some(Storage::Sqlite(s)), _) => s.read(location).map(|b| f(&b)),
            (Some(Storage::Mcap(_)), Location::Sqlite { .. }) => Err(RosError::Container {
                path: self.path.clone(),
                message: "no message at an SQLite row".to_owned(),
            }),
            (None, _) => Err(RosError::Container {
                path: self.path.clone(),
                message: format!("a message in file {}, not in the bag", location.file()),
            }),
        }
    }

    /// The records of chunk `key` of MCAP file `m`: kept ones, or decompressed (and kept).
    fn chunk(&self, m: &McapFile, key: ChunkKey) -> Result<Arc<ChunkRecords>, RosError> {
        let cache = || self.chunks.lock().unwrap_or_else(PoisonError::into_inner);
        if let Some(records) = cache().get(key) {
            return Ok(records);
        }
        let records = Arc::new(m.chunk_records(key.1)?);
        cache().put(key, Arc::clone(&records));
        Ok(records)
    }

    /// The bytes of message `index` of `topic` (as [`Bag::read`] or [`Bag::visit`] gave
    /// them), decoded as `T`.
    ///
    /// # Errors
    /// [`RosError::Decode`] naming the topic and message when the topic is of another type
    /// or the bytes do not decode.
    pub fn decode_bytes<T: RosMessage>(
        &self,
        topic: &Topic,
        index: usize,
        bytes: &[u8],
    ) -> Result<T, RosError> {
        let decode_error = |message: String| RosError::Decode {
            path: self.path.clone(),
            topic: topic.name.clone(),
            index,
            msg_type: topic.msg_type.clone(),
            message,
        };
        if topic.msg_type != T::TYPE {
            return Err(decode_error(format!("expected {}", T::TYPE)));
        }
        if topic.encoding != "cdr" {
            return Err(decode_error(format!(
                "serialisation '{}' (expected cdr)",
                topic.encoding
            )));
        }
        decode(bytes).map_err(|e| decode_error(e.0))
    }

    /// Message `index` of `topic`, decoded as `T`.
    ///
    /// # Errors
    /// As [`Bag::read`]; [`RosError::Decode`] naming the topic and message when the
    /// topic is of another type or the bytes do not decode.
    pub fn decode<T: RosMessage>(&self, topic: &Topic, index: usize) -> Result<T, RosError> {
        if topic.msg_type != T::TYPE || topic.encoding != "cdr" {
            return self.decode_bytes(topic, index, &[]);
        }
        self.with_message(topic, index, |bytes| self.decode_bytes(topic, index, bytes))?
    }
}
