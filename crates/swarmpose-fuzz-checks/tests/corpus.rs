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

/// A UTF-8 byte-order mark changes nothing (issue 29, cause 11): each `NAME_bom` entry of
/// the text corpora is entry `NAME` with the mark in front, and reads as it does.
#[test]
fn a_byte_order_mark_reads_as_the_text_without_it() {
    use swarmpose_eval::{Format, Trajectory};
    let corpus = fuzz_dir().join("corpus");
    let read = |target: &str, name: &str| -> (String, String) {
        let plain = std::fs::read_to_string(corpus.join(target).join(name)).expect("entry");
        let bom = std::fs::read_to_string(corpus.join(target).join(format!("{name}_bom")))
            .expect("BOM entry");
        assert_eq!(
            bom.strip_prefix('\u{feff}'),
            Some(plain.as_str()),
            "{target}/{name}_bom"
        );
        (plain, bom)
    };
    let path = Path::new("poses.txt");
    for (name, format) in [("kitti", Format::Kitti), ("tum", Format::Tum)] {
        let (plain, bom) = read("poses", name);
        let a = Trajectory::parse(&plain, path, format).expect("poses");
        let b = Trajectory::parse(&bom, path, format).expect("poses with a BOM");
        assert_eq!(a.poses, b.poses, "{name}");
        assert_eq!(a.stamps, b.stamps, "{name}");
    }
    let (plain, bom) = read("correspondence_csv", "plain");
    let a = swarmpose_data::correspondence_csv::read_from(plain.as_bytes(), "a.csv").expect("csv");
    let b = swarmpose_data::correspondence_csv::read_from(bom.as_bytes(), "b.csv")
        .expect("csv with a BOM");
    assert_eq!((a.src(), a.dst()), (b.src(), b.dst()));
    let csv = Path::new("mav0/state_groundtruth_estimate0/data.csv");
    let (plain, bom) = read("euroc_data_csv", "groundtruth");
    let a = swarmpose_datasets::euroc::parse_groundtruth(&plain, csv).expect("states");
    let b = swarmpose_datasets::euroc::parse_groundtruth(&bom, csv).expect("states with a BOM");
    assert_eq!(a, b);
    let csv = Path::new("mav0/cam0/data.csv");
    let (plain, bom) = read("euroc_data_csv", "images");
    let dir = Path::new("mav0/cam0");
    let a = swarmpose_datasets::euroc::parse_image_list(&plain, csv, dir).expect("images");
    let b = swarmpose_datasets::euroc::parse_image_list(&bom, csv, dir).expect("images with a BOM");
    assert_eq!(a, b);
}
