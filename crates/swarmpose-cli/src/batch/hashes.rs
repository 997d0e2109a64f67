//! The hashes a batch item's summary records, so that a rerun knows whether the item is
//! done: of the input (every file of the sequence folder, or the bag), of the effective
//! options, and the version.

use std::io::Read;
use std::path::{Path, PathBuf};

use clap::{Args, FromArgMatches};
use sha2::{Digest, Sha256};

use super::manifest::Item;
use crate::commands::odometry::OdometryArgs;
use crate::error::{CliError, from_clap};

/// The version recorded in every summary.
pub const VERSION: &str = env!("CARGO_PKG_VERSION");

fn hex(digest: &[u8]) -> String {
    use std::fmt::Write as _;
    let mut s = String::with_capacity(7 + 2 * digest.len());
    s.push_str("sha256:");
    for b in digest {
        let _ = write!(s, "{b:02x}");
    }
    s
}

/// Every regular file under `dir` (links followed), by path relative to `dir`.
fn files_under(dir: &Path, rel: &Path, out: &mut Vec<PathBuf>) -> std::io::Result<()> {
    for entry in std::fs::read_dir(dir.join(rel))? {
        let entry = entry?;
        let rel = rel.join(entry.file_name());
        let meta = std::fs::metadata(dir.join(&rel))?;
        if meta.is_dir() {
            files_under(dir, &rel, out)?;
        } else if meta.is_file() {
            out.push(rel);
        }
    }
    Ok(())
}

/// The SHA-256 of `input`: of a file, its bytes; of a folder, the relative path, length
/// and bytes of every regular file under it (links followed), in the order of their
/// paths. Every byte is read: a few seconds a gigabyte.
///
/// # Errors
/// Exit status 2 naming the file that cannot be read.
pub fn input_hash(input: &Path) -> Result<String, CliError> {
    let bad = |p: &Path, e: std::io::Error| CliError::usage(format!("{}: {e}", p.display()));
    let meta = std::fs::metadata(input).map_err(|e| bad(input, e))?;
    let mut files = Vec::new();
    if meta.is_dir() {
        files_under(input, Path::new(""), &mut files).map_err(|e| bad(input, e))?;
        files.sort();
    } else {
        files.push(PathBuf::new());
    }
    let mut h = Sha256::new();
    let mut buf = vec![0u8; 1 << 16];
    for rel in &files {
        // `input.join("")` would add a trailing '/', which a file's path cannot take.
        let path = if rel.as_os_str().is_empty() {
            input.to_owned()
        } else {
            input.join(rel)
        };
        let mut f = std::fs::File::open(&path).map_err(|e| bad(&path, e))?;
        let len = f.metadata().map_err(|e| bad(&path, e))?.len();
        h.update(rel.to_string_lossy().as_bytes());
        h.update([0]);
        h.update(len.to_le_bytes());
        loop {
            let n = f.read(&mut buf).map_err(|e| bad(&path, e))?;
            if n == 0 {
                break;
            }
            h.update(&buf[..n]);
        }
    }
    Ok(hex(&h.finalize()))
}

/// The hash of an item's inputs: its sequence's ([`input_hash`]), and with a ground-truth
/// file, the SHA-256 of both hashes (a changed ground truth makes the item run again).
///
/// # Errors
/// As [`input_hash`].
pub fn item_input_hash(item: &Item) -> Result<String, CliError> {
    let input = input_hash(&item.input)?;
    let Some(truth) = &item.ground_truth else {
        return Ok(input);
    };
    let mut h = Sha256::new();
    h.update(input.as_bytes());
    h.update([0]);
    h.update(input_hash(truth)?.as_bytes());
    Ok(hex(&h.finalize()))
}

/// `swarmpose odometry`'s options for `item`, parsed as the command parses them: `INPUT
/// --out OUT --quiet` then the item's options, where a later option overrides an earlier
/// one (an item's own over the shared ones).
///
/// # Errors
/// Exit status 2 with clap's message for a bad option.
pub fn odometry_args(item: &Item, out: &Path) -> Result<OdometryArgs, CliError> {
    let mut argv: Vec<std::ffi::OsString> = vec!["odometry".into()];
    if !item.input.as_os_str().is_empty() {
        argv.push(item.input.clone().into_os_string());
    }
    argv.extend(["--out".into(), out.as_os_str().to_owned(), "--quiet".into()]);
    argv.extend(item.args.iter().map(Into::into));
    let cmd = OdometryArgs::augment_args(clap::Command::new("odometry")).args_override_self(true);
    let matches = cmd.try_get_matches_from(argv).map_err(|e| from_clap(&e))?;
    OdometryArgs::from_arg_matches(&matches).map_err(|e| from_clap(&e))
}

/// The hash of an item's effective settings: the run configuration (`config.json`) its
/// options give, a `--config FILE`'s settings included (the input and output folders
/// left out).
///
/// # Errors
/// A bad option (exit status 2), or a `--config` file that cannot be read.
pub fn config_hash(item: &Item) -> Result<String, CliError> {
    let bare = Item {
        input: PathBuf::new(),
        ..item.clone()
    };
    let parsed = odometry_args(&bare, Path::new("."))?;
    // The run configuration the item's options give (a --config file's settings with the
    // options over them), as config.json records it: options that change nothing (the
    // default seed given explicitly) do not change the hash.
    let config = crate::commands::odometry::run_config(&parsed)?
        .to_json()
        .map_err(|e| CliError::usage(e.to_string()))?;
    let mut h = Sha256::new();
    h.update(config.as_bytes());
    Ok(hex(&h.finalize()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A bag is one file: its hash is of its bytes (the folder walk's empty relative path
    /// used to make `bag.mcap/`, which no file can be opened as).
    #[test]
    fn a_file_input_hashes_its_bytes() {
        let dir = tempfile::tempdir().expect("tempdir");
        let bag = dir.path().join("a.mcap");
        std::fs::write(&bag, b"bytes").expect("write");
        let first = input_hash(&bag).expect("hash of a file");
        std::fs::write(&bag, b"other").expect("write");
        assert_ne!(input_hash(&bag).expect("hash"), first);
    }

    fn item(args: &[&str]) -> Item {
        Item {
            name: "a".into(),
            input: PathBuf::from("/data/a"),
            args: args.iter().map(|s| (*s).to_owned()).collect(),
            ground_truth: None,
        }
    }

    #[test]
    fn the_config_hash_follows_the_effective_options_only() {
        let h = |a: &[&str]| config_hash(&item(a)).expect("hash");
        assert_eq!(h(&[]), h(&["--seed", "0"]), "0 is the default seed");
        assert_ne!(h(&[]), h(&["--seed", "1"]));
        assert_eq!(
            h(&["--seed", "0", "--seed", "1"]),
            h(&["--seed", "1"]),
            "the last wins"
        );
        let moved = Item {
            input: PathBuf::from("/elsewhere"),
            ..item(&[])
        };
        assert_eq!(config_hash(&moved).expect("hash"), h(&[]));
        let e = config_hash(&item(&["--no-such-option"])).expect_err("bad option");
        assert_eq!(e.code, 2);
    }
}
