//! Just enough of a rosbag2 `metadata.yaml`: the storage and the files of the bag
//! (`relative_file_paths`, as a block list or a flow list), and the compression mode
//! (a bag compressed file by file or message by message is refused by name).

use std::path::Path;

use crate::error::RosError;

/// What a `metadata.yaml` says about the bag's files.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Metadata {
    /// `storage_identifier`: `mcap` or `sqlite3`.
    pub storage: String,
    /// `relative_file_paths`, in order.
    pub files: Vec<String>,
}

/// Reads `path` as a rosbag2 `metadata.yaml`.
///
/// # Errors
/// [`RosError::Io`]; [`RosError::Container`] as [`parse_metadata`].
pub fn read_metadata(path: &Path) -> Result<Metadata, RosError> {
    let text = std::fs::read_to_string(path).map_err(|source| RosError::Io {
        path: path.to_owned(),
        what: "cannot read metadata.yaml",
        source,
    })?;
    parse_metadata(&text).map_err(|message| RosError::Container {
        path: path.to_owned(),
        message,
    })
}

/// A YAML scalar without its quotes.
fn unquote(s: &str) -> &str {
    let s = s.trim();
    s.strip_prefix('\'')
        .and_then(|x| x.strip_suffix('\''))
        .or_else(|| s.strip_prefix('"').and_then(|x| x.strip_suffix('"')))
        .unwrap_or(s)
}

/// The value of the first `key:` line (any indentation).
fn scalar<'a>(text: &'a str, key: &str) -> Option<&'a str> {
    text.lines().find_map(|l| {
        let (k, v) = l.trim_start().split_once(':')?;
        (k == key).then(|| unquote(v))
    })
}

/// The text of a `metadata.yaml`, parsed.
///
/// # Errors
/// A message for a missing or empty `relative_file_paths`, a file name that leaves the
/// folder, or a compressed bag.
pub fn parse_metadata(text: &str) -> Result<Metadata, String> {
    // A UTF-8 byte-order mark is accepted, as by every reader.
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    if !text.contains("rosbag2_bagfile_information") {
        return Err("not a rosbag2 metadata.yaml (no rosbag2_bagfile_information)".to_owned());
    }
    let mode = scalar(text, "compression_mode").unwrap_or("");
    if !mode.is_empty() && !mode.eq_ignore_ascii_case("none") {
        let format = scalar(text, "compression_format").unwrap_or("");
        return Err(format!(
            "the bag is compressed by {} ({format}): decompress it first (ros2 bag convert)",
            mode.to_lowercase()
        ));
    }
    let storage = scalar(text, "storage_identifier").unwrap_or("").to_owned();
    let mut lines = text
        .lines()
        .skip_while(|l| l.trim_start().split(':').next() != Some("relative_file_paths"));
    let first = lines
        .next()
        .ok_or("no relative_file_paths: the bag's files are not named")?;
    let rest = first.split_once(':').map_or("", |x| x.1).trim();
    let files: Vec<String> = if let Some(flow) = rest.strip_prefix('[') {
        flow.trim_end_matches(']')
            .split(',')
            .map(unquote)
            .filter(|s| !s.is_empty())
            .map(str::to_owned)
            .collect()
    } else {
        lines
            .take_while(|l| l.trim_start().starts_with('-') || l.trim().is_empty())
            .filter_map(|l| l.trim_start().strip_prefix('-'))
            .map(|s| unquote(s).to_owned())
            .collect()
    };
    if files.is_empty() {
        return Err("relative_file_paths is empty: the bag has no files".to_owned());
    }
    if let Some(bad) = files
        .iter()
        .find(|f| Path::new(f).is_absolute() || f.split(['/', '\\']).any(|c| c == ".."))
    {
        return Err(format!(
            "relative_file_paths names {bad}, outside the bag's folder"
        ));
    }
    Ok(Metadata { storage, files })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn block_and_flow_lists() {
        let block = "rosbag2_bagfile_information:\n  storage_identifier: mcap\n  \
                     relative_file_paths:\n    - a_0.mcap\n    - 'a_1.mcap'\n  files:\n";
        let m = parse_metadata(block).expect("block");
        assert_eq!(m.storage, "mcap");
        assert_eq!(m.files, ["a_0.mcap", "a_1.mcap"]);
        let flow = "rosbag2_bagfile_information:\n  relative_file_paths: [x.db3, \"y.db3\"]\n";
        assert_eq!(
            parse_metadata(flow).expect("flow").files,
            ["x.db3", "y.db3"]
        );
        let with_bom = format!("\u{feff}{block}");
        assert_eq!(
            parse_metadata(&with_bom).expect("a BOM is accepted").files,
            m.files
        );
    }

    #[test]
    fn refuses_what_it_cannot_read() {
        let head = "rosbag2_bagfile_information:\n";
        for (text, says) in [
            ("version: 4\n", "not a rosbag2"),
            ("rosbag2_bagfile_information:\n  version: 8\n", "not named"),
            (
                "rosbag2_bagfile_information:\n  relative_file_paths: []\n",
                "is empty",
            ),
            (
                "rosbag2_bagfile_information:\n  relative_file_paths:\n  - ../x.mcap\n",
                "outside",
            ),
        ] {
            let e = parse_metadata(text).expect_err(text);
            assert!(e.contains(says), "{e}");
        }
        let zstd = format!(
            "{head}  compression_format: zstd\n  compression_mode: FILE\n  relative_file_paths: [a.mcap.zstd]\n"
        );
        assert!(
            parse_metadata(&zstd)
                .expect_err("zstd")
                .contains("compressed by file (zstd)")
        );
    }
}
