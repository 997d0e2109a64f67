//! Every committed fuzz corpus input (`fuzz/corpus/TARGET/*`) passes its target's check,
//! in the ordinary test run; and the targets, the corpus folders and [`TARGETS`] name the
//! same set.

use std::path::{Path, PathBuf};

use swarmpose_fuzz_checks::TARGETS;

fn fuzz_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz")
}

/// The file stems in `dir` with extension `ext` (or every entry when `ext` is empty).
fn names_in(dir: &Path, ext: &str) -> Vec<String> {
    let mut names: Vec<String> = std::fs::read_dir(dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(Result::ok)
        .map(|e| e.path())
        .filter(|p| ext.is_empty() || p.extension().is_some_and(|x| x == ext))
        .filter_map(|p| p.file_stem().map(|s| s.to_string_lossy().into_owned()))
        .collect();
    names.sort();
    names
}

#[test]
fn every_target_has_a_corpus_and_a_check() {
    let mut listed: Vec<String> = TARGETS.iter().map(|(n, _)| (*n).to_owned()).collect();
    listed.sort();
    assert_eq!(names_in(&fuzz_dir().join("corpus"), ""), listed);
    assert_eq!(names_in(&fuzz_dir().join("fuzz_targets"), "rs"), listed);
    let manifest = std::fs::read_to_string(fuzz_dir().join("Cargo.toml")).expect("manifest");
    for name in &listed {
        assert!(
            manifest.contains(&format!("name = \"{name}\"")),
            "fuzz/Cargo.toml has no [[bin]] {name}"
        );
    }
}

#[test]
fn every_corpus_input_passes_its_check() {
    let mut total = 0;
    for (name, check) in TARGETS {
        let dir = fuzz_dir().join("corpus").join(name);
        let mut inputs = 0;
        for entry in std::fs::read_dir(&dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display())) {
            let path = entry.expect("entry").path();
            let data = std::fs::read(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
            let outcome = std::panic::catch_unwind(|| check(&data));
            assert!(
                outcome.is_ok(),
                "{name}: {} fails its check",
                path.display()
            );
            inputs += 1;
        }
        assert!(inputs > 0, "{name}: empty corpus");
        total += inputs;
    }
    eprintln!(
        "{total} corpus inputs replayed over {} targets",
        TARGETS.len()
    );
}
