//! The manifest of a batch: a TOML file listing the items (a sequence folder or a ROS 2
//! bag each) and the `swarmpose odometry` options they run with.
//!
//! ```toml
//! # For every item (both optional):
//! config = "run.json"            # given to each item as `--config FILE`
//! args = ["--window", "10"]      # more `swarmpose odometry` options
//!
//! [[item]]
//! input = "data/kitti_vo_seq2"   # a sequence folder or a bag
//! name = "kitti02"               # optional: the input's file name by default
//! args = ["--frame-period", "0.2"]  # optional: this item's own options, after the shared
//! ground_truth = "data/02.txt"   # optional: the left camera's true poses (KITTI, or TUM
//!                                # for a bag), as `--ground-truth FILE`
//! ```
//!
//! Paths are relative to the manifest's folder. Names are unique and made of letters,
//! digits, `.`, `_` and `-` (each is a folder of the output). Item `k` (from 0, in the
//! manifest's order) belongs to shard `k mod N + 1` of `N`.

use std::path::{Path, PathBuf};

use serde::Deserialize;
pub use swarmpose_sim::Shard;

use crate::error::CliError;

/// The manifest's text.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ManifestFile {
    config: Option<PathBuf>,
    #[serde(default)]
    args: Vec<String>,
    #[serde(default)]
    item: Vec<ItemFile>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct ItemFile {
    input: PathBuf,
    name: Option<String>,
    ground_truth: Option<PathBuf>,
    #[serde(default)]
    args: Vec<String>,
}

/// One item of a batch.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Item {
    /// Its name: the folder of its outputs under the batch's output folder.
    pub name: String,
    /// The sequence folder or bag (resolved against the manifest's folder).
    pub input: PathBuf,
    /// Its `swarmpose odometry` options: `--config FILE`, the shared options, its own,
    /// and `--ground-truth FILE` when it has one.
    pub args: Vec<String>,
    /// Its ground-truth file, when the manifest gives one (resolved against its folder).
    pub ground_truth: Option<PathBuf>,
}

/// A batch's items, in the manifest's order.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct Manifest {
    /// Every item.
    pub items: Vec<Item>,
}

/// Whether `name` can be an item's folder: letters, digits, `.`, `_`, `-`, not starting
/// with `.`, at most 200 bytes.
fn valid_name(name: &str) -> bool {
    !name.is_empty()
        && name.len() <= 200
        && !name.starts_with('.')
        && name
            .chars()
            .all(|c| c.is_ascii_alphanumeric() || matches!(c, '.' | '_' | '-'))
}

impl Manifest {
    /// Reads and checks the manifest at `path`.
    ///
    /// # Errors
    /// Exit status 2 naming the manifest: unreadable, not TOML of the format above, no
    /// item, a bad or repeated name.
    pub fn load(path: &Path) -> Result<Self, CliError> {
        let text = std::fs::read_to_string(path)
            .map_err(|e| CliError::usage(format!("{}: cannot read: {e}", path.display())))?;
        Self::parse(&text, path.parent().unwrap_or(Path::new("")))
            .map_err(|e| CliError::usage(format!("{}: {e}", path.display())))
    }

    /// Parses a manifest's `text`, paths relative to `base`.
    ///
    /// # Errors
    /// As [`Manifest::load`], without the file's name.
    pub fn parse(text: &str, base: &Path) -> Result<Self, String> {
        // A UTF-8 byte-order mark is accepted, as by every reader.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let file: ManifestFile = toml::from_str(text).map_err(|e| {
            format!(
                "not a batch manifest: {}",
                crate::error::one_line(&e.to_string())
            )
        })?;
        if file.item.is_empty() {
            return Err("no [[item]]: a manifest lists at least one item".into());
        }
        let mut shared = Vec::new();
        if let Some(c) = &file.config {
            shared.push("--config".to_owned());
            shared.push(base.join(c).to_string_lossy().into_owned());
        }
        shared.extend(file.args.iter().cloned());
        let mut items: Vec<Item> = Vec::with_capacity(file.item.len());
        for (k, it) in file.item.into_iter().enumerate() {
            let name = match it.name {
                Some(n) => n,
                None => it
                    .input
                    .file_name()
                    .map(|n| n.to_string_lossy().into_owned())
                    .unwrap_or_default(),
            };
            if !valid_name(&name) {
                return Err(format!(
                    "item {} ({}): name '{name}' is not a folder name of letters, digits, '.', \
                     '_' and '-' (give one with name = \"...\")",
                    k + 1,
                    it.input.display()
                ));
            }
            if items.iter().any(|i| i.name == name) {
                return Err(format!(
                    "item {}: the name '{name}' is used twice (give one with name = \"...\")",
                    k + 1
                ));
            }
            let mut args = shared.clone();
            args.extend(it.args);
            let ground_truth = it.ground_truth.map(|g| base.join(g));
            if let Some(g) = &ground_truth {
                args.push("--ground-truth".to_owned());
                args.push(g.to_string_lossy().into_owned());
            }
            items.push(Item {
                name,
                input: base.join(it.input),
                args,
                ground_truth,
            });
        }
        Ok(Self { items })
    }

    /// The items of `shard`, in the manifest's order.
    #[must_use]
    pub fn shard(&self, shard: Shard) -> Vec<&Item> {
        self.items
            .iter()
            .enumerate()
            .filter(|(k, _)| shard.holds(*k))
            .map(|(_, i)| i)
            .collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn items_resolve_paths_and_take_the_shared_options_first() {
        let m = Manifest::parse(
            "config = \"c.json\"\nargs = [\"--window\", \"4\"]\n\
             [[item]]\ninput = \"data/seq\"\n\
             [[item]]\ninput = \"b.mcap\"\nname = \"bag\"\nargs = [\"--seed\", \"3\"]\n",
            Path::new("/m"),
        )
        .expect("manifest");
        assert_eq!(m.items[0].name, "seq");
        assert_eq!(m.items[0].input, Path::new("/m/data/seq"));
        assert_eq!(
            m.items[1].args,
            ["--config", "/m/c.json", "--window", "4", "--seed", "3"]
        );
    }

    #[test]
    fn an_items_ground_truth_becomes_its_last_option() {
        let m = Manifest::parse(
            "args = [\"--window\", \"4\"]\n[[item]]\ninput = \"b.mcap\"\nground_truth = \"gt/b.tum.txt\"\n",
            Path::new("/m"),
        )
        .expect("manifest");
        assert_eq!(
            m.items[0].ground_truth.as_deref(),
            Some(Path::new("/m/gt/b.tum.txt"))
        );
        assert_eq!(
            m.items[0].args,
            ["--window", "4", "--ground-truth", "/m/gt/b.tum.txt"]
        );
    }

    #[test]
    fn bad_manifests_are_refused_with_the_reason() {
        let err = |t: &str| Manifest::parse(t, Path::new("")).expect_err(t);
        assert!(err("").contains("no [[item]]"));
        let bom = Manifest::parse("\u{feff}[[item]]\ninput = \"a\"\n", Path::new(""));
        assert_eq!(bom.expect("a BOM is accepted").items.len(), 1);
        assert!(err("[[item]]\ninput = \"a\"\n[[item]]\ninput = \"x/a\"\n").contains("twice"));
        assert!(err("[[item]]\ninput = \"a\"\nname = \"../x\"\n").contains("not a folder name"));
        assert!(err("[[item]]\ninput = \"a\"\nframes = 3\n").contains("not a batch manifest"));
    }

    #[test]
    fn shards_split_the_items_round_robin() {
        assert_eq!("2/3".parse::<Shard>(), Ok(Shard { index: 2, count: 3 }));
        for bad in ["0/3", "4/3", "1", "a/b", "1/0"] {
            assert!(bad.parse::<Shard>().is_err(), "{bad}");
        }
        let text: String = (0..8)
            .map(|k| format!("[[item]]\ninput = \"i{k}\"\n"))
            .collect();
        let m = Manifest::parse(&text, Path::new("")).expect("manifest");
        let names: Vec<&str> = m
            .shard(Shard { index: 2, count: 3 })
            .iter()
            .map(|i| i.name.as_str())
            .collect();
        assert_eq!(names, ["i1", "i4", "i7"]);
        assert_eq!(Shard { index: 2, count: 3 }.len_of(8), 3);
    }
}
