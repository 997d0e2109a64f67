//! `swarmpose batch`: the shared real sequences (their first 8 frames) and exact
//! variants of the KITTI clip (tools/variants) run serially, in 2 and in 3 shards give
//! the same merged table byte for byte; a batch killed mid-way finishes only what was
//! missing when run again, and an item with a corrupt frame is reported with its status
//! while the others succeed. `simulate` in 2 shards merges into a single run's runs.csv.

use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::{Duration, Instant};

use crate::common::{TempDir, assert_success, shared_dataset, swarmpose};

/// Frames of each slice of a real sequence (few: the test runs every item three times).
const FRAMES: usize = 8;

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

fn link(src: &Path, dst: &Path) {
    std::os::unix::fs::symlink(src, dst).expect("symlink");
}

/// The first `n` lines of `src`'s text in `dst`.
fn head(src: &Path, dst: &Path, n: usize) {
    let text = std::fs::read_to_string(src).expect("read");
    let lines: Vec<&str> = text.lines().take(n).collect();
    std::fs::write(dst, format!("{}\n", lines.join("\n"))).expect("write");
}

/// Sorted file names of `dir`.
fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .expect("list")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .collect();
    v.sort();
    v
}

/// The first `FRAMES` frames of the KITTI clip (images linked, poses cut).
fn kitti_slice(src: &Path, dst: &Path) {
    for cam in ["image_0", "image_1"] {
        std::fs::create_dir_all(dst.join(cam)).expect("mkdir");
        for f in names(&src.join(cam)).iter().take(FRAMES) {
            link(&src.join(cam).join(f), &dst.join(cam).join(f));
        }
    }
    link(&src.join("calib.txt"), &dst.join("calib.txt"));
    head(&src.join("poses.txt"), &dst.join("poses.txt"), FRAMES);
}

/// The first `FRAMES` frames of the Karlsruhe sequence.
fn karlsruhe_slice(src: &Path, dst: &Path) {
    let images = "2010_03_09_drive_0023_Images";
    std::fs::create_dir_all(dst.join(images)).expect("mkdir");
    let all = names(&src.join(images));
    for prefix in ["I1_", "I2_"] {
        for f in all.iter().filter(|f| f.starts_with(prefix)).take(FRAMES) {
            link(&src.join(images).join(f), &dst.join(images).join(f));
        }
    }
    link(&src.join("calib.txt"), &dst.join("calib.txt"));
}

/// The first `FRAMES` frames of the EuRoC clip (the image lists cut).
fn euroc_slice(src: &Path, dst: &Path) {
    let (m, d) = (src.join("mav0"), dst.join("mav0"));
    std::fs::create_dir_all(&d).expect("mkdir");
    for entry in names(&m) {
        if entry == "cam0" || entry == "cam1" {
            std::fs::create_dir_all(d.join(&entry)).expect("mkdir");
            for f in names(&m.join(&entry)) {
                if f == "data.csv" {
                    head(
                        &m.join(&entry).join(&f),
                        &d.join(&entry).join(&f),
                        FRAMES + 1,
                    );
                } else {
                    link(&m.join(&entry).join(&f), &d.join(&entry).join(&f));
                }
            }
        } else {
            link(&m.join(&entry), &d.join(&entry));
        }
    }
}

/// Whether `python3` with numpy runs here (tools/variants needs them); under CI it must.
fn python_with_numpy() -> bool {
    let ok = Command::new("python3")
        .args(["-c", "import numpy"])
        .stderr(Stdio::null())
        .status()
        .is_ok_and(|s| s.success());
    assert!(
        ok || std::env::var("CI").map_or(true, |v| v != "true"),
        "CI=true: python3 with numpy is needed for tools/variants"
    );
    if !ok {
        eprintln!("SKIPPED (variants): python3 with numpy not found");
    }
    ok
}

/// The exact variants of `kitti` that need no image processing (tools/variants).
fn variants(kitti: &Path, dst: &Path) -> Vec<PathBuf> {
    let only = ["reversed", "first-half", "second-half", "every-2nd"];
    if !python_with_numpy() {
        return Vec::new();
    }
    let tool = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/variants/kitti_variants.py");
    let out = Command::new("python3")
        .arg(&tool)
        .args([s(kitti), s(dst), "--only"])
        .args(only)
        .output()
        .expect("run kitti_variants.py");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    only.iter().map(|v| dst.join(v)).collect()
}

/// Slices of the KITTI and the Karlsruhe sequences in `tmp/seq`, or `None` when the
/// shared data is absent.
fn kitti_and_karlsruhe(tmp: &TempDir) -> Option<(PathBuf, PathBuf)> {
    let kitti = shared_dataset("kitti_vo_seq2")?;
    let karlsruhe = shared_dataset("karlsruhe_2010_03_09_drive_0023")?;
    let k = tmp.0.join("seq/kitti");
    kitti_slice(&kitti, &k);
    let ka = tmp.0.join("seq/karlsruhe");
    karlsruhe_slice(&karlsruhe, &ka);
    Some((k, ka))
}

/// The sequences of the batch (name, folder, extra options), or `None` when the shared
/// data is absent.
fn sequences(tmp: &TempDir) -> Option<Vec<(String, PathBuf, &'static str)>> {
    let euroc = shared_dataset("euroc_v1_01_easy_micro")?;
    let (k, ka) = kitti_and_karlsruhe(tmp)?;
    let eu = tmp.0.join("seq/euroc");
    euroc_slice(&euroc, &eu);
    let mut v = vec![
        ("kitti".to_owned(), k.clone(), ""),
        ("karlsruhe".to_owned(), ka, ""),
        ("euroc".to_owned(), eu, ""),
    ];
    for dir in variants(&k, &tmp.0.join("variants")) {
        let name = format!(
            "kitti-{}",
            dir.file_name()
                .map_or(String::new(), |n| n.to_string_lossy().into_owned())
        );
        let opts = if name.ends_with("every-2nd") {
            "\"--frame-period\", \"0.2\""
        } else {
            ""
        };
        v.push((name, dir, opts));
    }
    Some(v)
}

fn manifest(tmp: &TempDir, items: &[(String, PathBuf, &str)]) -> PathBuf {
    let mut text = String::from("args = [\"--seed\", \"0\"]\n");
    for (name, dir, opts) in items {
        text.push_str(&format!(
            "\n[[item]]\nname = \"{name}\"\ninput = \"{}\"\nargs = [{opts}]\n",
            s(dir)
        ));
    }
    tmp.file("manifest.toml", &text)
}

fn batch(args: &[&str]) -> std::process::Output {
    let out = swarmpose(args, None);
    assert_success(&out);
    out
}

fn read(p: &Path) -> String {
    std::fs::read_to_string(p).unwrap_or_else(|e| panic!("{}: {e}", p.display()))
}

#[test]
fn shards_merge_into_the_serial_table_byte_for_byte() {
    let tmp = TempDir::new("batch-shards");
    let Some(items) = sequences(&tmp) else { return };
    let m = manifest(&tmp, &items);
    let serial = tmp.0.join("serial");
    batch(&["batch", s(&m), "--out", s(&serial)]);
    batch(&["batch", "merge", s(&serial)]);
    // Two shards in two folders, merged into a third.
    let (a, b, two) = (tmp.0.join("2a"), tmp.0.join("2b"), tmp.0.join("2"));
    batch(&[
        "batch",
        s(&m),
        "--out",
        s(&a),
        "--shard",
        "1/2",
        "--jobs",
        "2",
    ]);
    batch(&[
        "batch",
        s(&m),
        "--out",
        s(&b),
        "--shard",
        "2/2",
        "--jobs",
        "2",
    ]);
    batch(&["batch", "merge", s(&a), s(&b), "--out", s(&two)]);
    // Three shards into one folder.
    let three = tmp.0.join("3");
    for i in 1..=3 {
        batch(&[
            "batch",
            s(&m),
            "--out",
            s(&three),
            "--shard",
            &format!("{i}/3"),
            "--jobs",
            "2",
        ]);
    }
    batch(&["batch", "merge", s(&three)]);
    let table = read(&serial.join("batch.csv"));
    assert_eq!(table.lines().count(), items.len() + 1, "{table}");
    for (name, ..) in &items {
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("{name},")))
            .expect(name);
        assert!(row.starts_with(&format!("{name},ok,0,")), "{row}");
    }
    // With ground truth (KITTI and its variants, EuRoC), the figures are there: path,
    // final error, eq. (20), ATE (a drift in percent needs 10 cm of path: the EuRoC clip
    // stands still; the KITTI segment errors need 100 m).
    for name in ["kitti", "kitti-reversed", "euroc"] {
        let row = table
            .lines()
            .find(|l| l.starts_with(&format!("{name},")))
            .expect(name);
        let cells: Vec<&str> = row.split(',').collect();
        assert!(
            [7, 8, 10, 11].iter().all(|&c| !cells[c].is_empty()),
            "{row}"
        );
    }
    for name in ["batch.csv", "batch.md"] {
        let want = read(&serial.join(name));
        assert_eq!(read(&two.join(name)), want, "2 shards: {name}");
        assert_eq!(read(&three.join(name)), want, "3 shards: {name}");
    }
}

/// A KITTI slice whose frame 3 is not an image.
fn corrupt_copy(kitti: &Path, dst: &Path) {
    for cam in ["image_0", "image_1"] {
        std::fs::create_dir_all(dst.join(cam)).expect("mkdir");
        for f in names(&kitti.join(cam)) {
            link(&kitti.join(cam).join(&f), &dst.join(cam).join(&f));
        }
    }
    let bad = dst.join("image_0/000003.png");
    std::fs::remove_file(&bad).expect("unlink");
    std::fs::write(&bad, b"\x89PNG\r\n\x1a\nnot really a png").expect("corrupt");
    link(&kitti.join("calib.txt"), &dst.join("calib.txt"));
    link(&kitti.join("poses.txt"), &dst.join("poses.txt"));
}

#[test]
fn a_killed_batch_finishes_only_what_was_missing_and_a_bad_item_fails_alone() {
    let tmp = TempDir::new("batch-resume");
    let Some((k, ka)) = kitti_and_karlsruhe(&tmp) else {
        return;
    };
    let bad = tmp.0.join("seq/corrupt");
    corrupt_copy(&k, &bad);
    let items = vec![
        ("a-kitti".to_owned(), k.clone(), ""),
        ("b-corrupt".to_owned(), bad, ""),
        ("c-karlsruhe".to_owned(), ka, ""),
        ("d-kitti-seed1".to_owned(), k, "\"--seed\", \"1\""),
    ];
    let m = manifest(&tmp, &items);
    let out = tmp.0.join("out");
    let mut child = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .args(["batch", s(&m), "--out", s(&out)])
        .stdout(Stdio::null())
        .stderr(Stdio::null())
        .spawn()
        .expect("run batch");
    // Kill it (SIGKILL: nothing of it runs after) once the first item is done.
    let start = Instant::now();
    while !out.join("a-kitti/summary.json").exists() {
        assert!(
            start.elapsed() < Duration::from_secs(120),
            "first item never finished"
        );
        std::thread::sleep(Duration::from_millis(10));
    }
    child.kill().expect("kill");
    let _ = child.wait();
    let done_before: Vec<&str> = items
        .iter()
        .map(|(n, ..)| n.as_str())
        .filter(|n| out.join(n).join("summary.json").exists())
        .collect();
    assert!(
        done_before.len() < items.len(),
        "killed too late: {done_before:?}"
    );
    let first = read(&out.join("a-kitti/summary.json"));
    let again = swarmpose(&["batch", s(&m), "--out", s(&out)], None);
    let stdout = String::from_utf8_lossy(&again.stdout);
    let stderr = String::from_utf8_lossy(&again.stderr);
    assert_eq!(
        again.status.code(),
        Some(1),
        "the corrupt item fails: {stdout}{stderr}"
    );
    assert!(
        stderr.contains("1 of 4 item(s) did not succeed (b-corrupt)"),
        "{stderr}"
    );
    for (name, ..) in &items {
        let skipped = stdout.contains(&format!("{name}: ok (done before: skipped)"));
        assert_eq!(
            skipped,
            done_before.contains(&name.as_str()),
            "{name}: {stdout}"
        );
    }
    assert_eq!(
        read(&out.join("a-kitti/summary.json")),
        first,
        "not run again"
    );
    let corrupt: serde_json::Value =
        serde_json::from_str(&read(&out.join("b-corrupt/summary.json"))).expect("json");
    assert_eq!(corrupt["status"], "failed");
    assert_eq!(corrupt["exit_code"], 2);
    assert_eq!(
        corrupt["frames"], 3,
        "the frames before the corrupt one are kept"
    );
    let message = corrupt["message"].as_str().expect("message");
    assert!(
        message.starts_with("frame 3: ") && message.contains("000003.png"),
        "{message}"
    );
    let merged = swarmpose(&["batch", "merge", s(&out)], None);
    assert_eq!(
        merged.status.code(),
        Some(3),
        "{}",
        String::from_utf8_lossy(&merged.stderr)
    );
    let table = read(&out.join("batch.csv"));
    assert!(table.contains("\nb-corrupt,failed,2,3,"), "{table}");
    assert!(
        table.contains(&format!("\nc-karlsruhe,ok,0,{FRAMES},")),
        "{table}"
    );
    // A third run has nothing left but the bad item.
    let third = swarmpose(&["batch", s(&m), "--out", s(&out)], None);
    let stdout = String::from_utf8_lossy(&third.stdout);
    assert!(stdout.contains("3 done before"), "{stdout}");
}

/// `runs.csv` without its `elapsed_ms` column (a measured time).
fn without_times(csv: &str) -> String {
    let col = csv
        .lines()
        .next()
        .and_then(|h| h.split(',').position(|c| c == "elapsed_ms"))
        .expect("elapsed_ms column");
    csv.lines()
        .map(|l| {
            // No field before elapsed_ms holds a comma (the estimator names do not).
            let mut f: Vec<&str> = l.splitn(col + 2, ',').collect();
            f.remove(col);
            f.join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn simulate_in_two_shards_merges_into_the_single_runs_csv() {
    let tmp = TempDir::new("batch-sim");
    let grid = [
        "--runs",
        "3",
        "--noise",
        "0,0.05",
        "--fractions",
        "0,0.5",
        "--threads",
        "2",
    ];
    let single = tmp.0.join("single");
    let run = |out: &Path, shard: Option<&str>| {
        let mut args = vec!["simulate", "--out", s(out)];
        args.extend(grid);
        if let Some(sh) = shard {
            args.extend(["--shard", sh]);
        }
        batch(&args);
    };
    run(&single, None);
    let (a, b, merged) = (tmp.0.join("a"), tmp.0.join("b"), tmp.0.join("merged"));
    run(&a, Some("1/2"));
    run(&b, Some("2/2"));
    let only_one = swarmpose(&["batch", "merge", s(&a), "--out", s(&merged)], None);
    assert_eq!(only_one.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&only_one.stderr).contains("shard(s) 2/2 missing"));
    batch(&["batch", "merge", s(&b), s(&a), "--out", s(&merged)]);
    let want = read(&single.join("runs.csv"));
    assert_eq!(want.lines().count(), 1 + 2 * 2 * 3 * 4, "{want}");
    assert_eq!(
        without_times(&read(&merged.join("runs.csv"))),
        without_times(&want)
    );
    for f in ["summary.md", "success_rate.png", "position_error.svg"] {
        assert!(merged.join(f).is_file(), "{f}");
    }
}

/// An item's `ground_truth` file stands in for the poses a sequence carries: the KITTI
/// slice with its `poses.txt` moved away and named in the manifest gives the metrics of the
/// slice that holds it; a ground truth of another length fails that item alone (exit 2).
#[test]
fn an_items_ground_truth_file_gives_the_metrics_of_the_sequences_own() {
    let tmp = TempDir::new("batch-truth");
    let Some(kitti) = shared_dataset("kitti_vo_seq2") else {
        return;
    };
    let with = tmp.0.join("seq/with");
    kitti_slice(&kitti, &with);
    let without = tmp.0.join("seq/without");
    kitti_slice(&kitti, &without);
    let truth = tmp.0.join("truth.txt");
    std::fs::rename(without.join("poses.txt"), &truth).expect("move poses");
    let short = tmp.0.join("short.txt");
    head(&truth, &short, FRAMES - 1);
    let text = format!(
        "[[item]]\nname = \"own\"\ninput = \"{}\"\n\
         [[item]]\nname = \"given\"\ninput = \"{}\"\nground_truth = \"{}\"\n\
         [[item]]\nname = \"short\"\ninput = \"{}\"\nground_truth = \"{}\"\n",
        s(&with),
        s(&without),
        s(&truth),
        s(&without),
        s(&short)
    );
    let m = tmp.file("truth.toml", &text);
    let out = tmp.0.join("out");
    let run = swarmpose(&["batch", s(&m), "--out", s(&out)], None);
    assert_ne!(run.status.code(), Some(0), "the short item fails");
    let summary = |name: &str| -> serde_json::Value {
        serde_json::from_str(&read(&out.join(name).join("summary.json"))).expect("json")
    };
    let own = summary("own");
    let given = summary("given");
    let (own, given) = (&own["metrics"], &given["metrics"]);
    let figures = own
        .as_object()
        .expect("the sequence's own ground truth gives metrics");
    // The same poses, read by two readers (the KITTI loader's and evaluate's, which
    // projects each matrix onto the nearest rotation): equal to rounding.
    for (key, value) in figures {
        match (value.as_f64(), given[key].as_f64()) {
            (Some(a), Some(b)) => {
                assert!((a - b).abs() <= 1e-9 * a.abs().max(1e-3), "{key}: {a} {b}")
            }
            _ => assert_eq!(value, &given[key], "{key}"),
        }
    }
    let short = summary("short");
    assert_eq!(short["status"], "failed");
    assert_eq!(short["exit_code"], 2);
    let message = short["message"].as_str().expect("message");
    assert!(
        message.contains(&format!(
            "{} KITTI pose(s) for a sequence of {FRAMES} frames",
            FRAMES - 1
        )),
        "{message}"
    );
}
