//! MCAP bags written at test time with the `mcap` crate's writer (profile `ros2`,
//! schemas in `ros2msg` from [`swarmpose_ros::msg::schema_text`], CDR messages): for the
//! tests and the benchmark of swarmpose-ros and the command line's tests.

use std::collections::BTreeMap;
use std::collections::btree_map::Entry;
use std::path::Path;

use mcap::records::MessageHeader;
use mcap::{Compression, WriteOptions};
use swarmpose_ros::msg::schema_text;

/// A topic to write: name, type, and `(log time ns, CDR bytes)` messages.
pub type TopicData = (&'static str, &'static str, Vec<(i64, Vec<u8>)>);

/// Writes `messages` (`(topic, type, log time ns, CDR bytes)`, in this order) as an MCAP
/// bag at `path`, chunked with `compression`, with its summary; a topic's channel (and
/// its type's schema) is added where the topic first appears.
///
/// # Panics
/// When the file cannot be written (meant for tests only).
pub fn write_mcap_messages<'a>(
    path: &Path,
    messages: impl IntoIterator<Item = (&'a str, &'a str, i64, &'a [u8])>,
    compression: Option<Compression>,
) {
    let file = std::io::BufWriter::new(std::fs::File::create(path).expect("create the bag"));
    let mut w = WriteOptions::new()
        .profile("ros2")
        .compression(compression)
        .create(file)
        .expect("mcap writer");
    // Each channel's id and the number of messages written on it.
    let mut channels: BTreeMap<&str, (u16, u32)> = BTreeMap::new();
    for (topic, ty, t, data) in messages {
        let (id, sequence) = match channels.entry(topic) {
            Entry::Occupied(e) => e.into_mut(),
            Entry::Vacant(e) => {
                let text = schema_text(ty).unwrap_or_default();
                let schema = w
                    .add_schema(ty, "ros2msg", text.as_bytes())
                    .expect("schema");
                let id = w
                    .add_channel(schema, topic, "cdr", &BTreeMap::new())
                    .expect("channel");
                e.insert((id, 0))
            }
        };
        let header = MessageHeader {
            channel_id: *id,
            sequence: *sequence,
            log_time: t as u64,
            publish_time: t as u64,
        };
        *sequence += 1;
        w.write_to_known_channel(&header, data).expect("write");
    }
    w.finish().expect("finish the bag");
}

/// Writes `topics` as an MCAP bag at `path`, one topic after the other, in zstd chunks.
///
/// # Panics
/// As [`write_mcap_messages`].
pub fn write_mcap(path: &Path, topics: &[TopicData]) {
    write_mcap_messages(
        path,
        topics.iter().flat_map(|(name, ty, msgs)| {
            msgs.iter()
                .map(move |(t, data)| (*name, *ty, *t, data.as_slice()))
        }),
        Some(Compression::Zstd),
    );
}
