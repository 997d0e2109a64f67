//! No output option of any command replaces what is not a regular file (issue 29, cause
//! 1): run as root, `correspondences --out /dev/stdout` renamed its temporary file over
//! `/dev/stdout` (and `/dev/full` likewise) for the whole machine, saying "written". Now
//! a FIFO or a character device is written through, a folder is refused, and links to
//! either stay links. The nodes are made here, in a temporary folder (copies of
//! `/dev/null` and `/dev/full` by `mknod`, which needs root: skipped with the reason
//! otherwise); the real `/dev` nodes are never touched.

use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};

use crate::catalogue::{expect, kitti, s, succeeded};
use crate::common::{TempDir, swarmpose};

/// A copy of `/dev/null` (`full`: of `/dev/full`) made in `dir`, or `None` with the
/// reason printed.
fn device(dir: &Path, name: &str, full: bool) -> Option<PathBuf> {
    let path = dir.join(name);
    let minor = if full { "7" } else { "3" };
    let made = Command::new("mknod")
        .arg(&path)
        .args(["c", "1", minor])
        .status()
        .is_ok_and(|st| st.success());
    if !made {
        eprintln!("SKIPPED: mknod not permitted here (needs root)");
    }
    made.then_some(path)
}

fn fifo(dir: &Path, name: &str) -> PathBuf {
    let path = dir.join(name);
    let made = Command::new("mkfifo").arg(&path).status().expect("mkfifo");
    assert!(made.success(), "mkfifo");
    path
}

fn is_char_device(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_char_device())
}

fn is_link(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_symlink())
}

/// Checks the one-line error of writing into the copy of `/dev/full` (or a link to it)
/// at `path`.
fn no_space(out: &std::process::Output, path: &Path) {
    expect(
        out,
        1,
        &format!(
            "swarmpose: error: {}: cannot write: No space left on device",
            s(path)
        ),
    );
}

/// Reads the FIFO `path` whole in a thread (the writer's open waits for it).
fn drain(path: &Path) -> std::thread::JoinHandle<String> {
    let path = path.to_owned();
    std::thread::spawn(move || std::fs::read_to_string(path).expect("read FIFO"))
}

/// Names in `dir` that are temporaries of a writer.
fn temporaries(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .expect("list")
        .filter_map(|e| e.ok()?.file_name().into_string().ok())
        .filter(|n| n.contains(".partial-"))
        .collect()
}

#[test]
fn correspondences_writes_through_a_fifo_a_device_and_a_pipe() {
    let tmp = TempDir::new("special-corr");
    let Some(seq) = kitti(&tmp.0, "k", 2) else {
        return;
    };
    let corr = |out: &Path, extra: &[&str]| {
        let mut args = vec!["correspondences", s(&seq), "--frames", "0", "1"];
        args.extend(["--out", s(out)]);
        args.extend(extra);
        swarmpose(&args, None)
    };
    // A FIFO: its reader gets the CSV; the FIFO stays a FIFO.
    let pipe = fifo(&tmp.0, "pipe.csv");
    let reader = drain(&pipe);
    let out = corr(&pipe, &[]);
    succeeded(&out);
    let text = reader.join().expect("reader");
    assert!(text.starts_with("src_x,src_y,src_z,dst_x") && text.lines().count() > 100);
    assert!(
        std::fs::symlink_metadata(&pipe)
            .expect("pipe")
            .file_type()
            .is_fifo()
    );
    // A link to this process's standard output, as /dev/stdout is: `--out /dev/stdout |
    // swarmpose register -` streams the CSV, and the link stays.
    let stdout = tmp.0.join("stdout");
    std::os::unix::fs::symlink("/proc/self/fd/1", &stdout).expect("link");
    let out = corr(&stdout, &[]);
    succeeded(&out);
    let piped = String::from_utf8_lossy(&out.stdout);
    assert!(piped.starts_with("src_x,src_y,src_z,dst_x") && piped.lines().count() > 100);
    assert!(is_link(&stdout));
    // A folder: refused before any work, nothing written into it.
    let folder = tmp.0.join("folder");
    std::fs::create_dir(&folder).expect("mkdir");
    expect(
        &corr(&folder, &[]),
        1,
        &format!(
            "swarmpose: error: {}: cannot write: a folder, not a file",
            s(&folder)
        ),
    );
    assert_eq!(std::fs::read_dir(&folder).expect("list").count(), 0);
    let Some(null) = device(&tmp.0, "null", false) else {
        return;
    };
    let full = device(&tmp.0, "full", true).expect("mknod");
    let to_full = tmp.0.join("to-full.png");
    std::os::unix::fs::symlink(&full, &to_full).expect("link");
    // --out and --draw into a device: written through, the nodes stay.
    let out = corr(&null, &["--draw", s(&null)]);
    succeeded(&out);
    no_space(&corr(&full, &[]), &full);
    let csv = tmp.0.join("c.csv");
    no_space(&corr(&csv, &["--draw", s(&to_full)]), &to_full);
    assert!(is_char_device(&null) && is_char_device(&full) && is_link(&to_full));
    assert!(temporaries(&tmp.0).is_empty(), "{:?}", temporaries(&tmp.0));
}

#[test]
fn bench_simulate_and_odometry_outputs_never_replace_a_device() {
    let tmp = TempDir::new("special-sim");
    let Some(full) = device(&tmp.0, "full", true) else {
        return;
    };
    let null = device(&tmp.0, "null", false).expect("mknod");
    // bench --runs-csv.
    let bench = |csv: &Path| {
        swarmpose(
            &[
                "bench",
                "--stereo",
                "1",
                "--methods",
                "svd",
                "--runs-csv",
                s(csv),
            ],
            None,
        )
    };
    let out = bench(&null);
    succeeded(&out);
    no_space(&bench(&full), &full);
    // simulate --out with runs.csv a link to a device, --export into a folder whose
    // scenario file is a device.
    let sim_dir = tmp.0.join("sim");
    let export = tmp.0.join("export");
    std::fs::create_dir_all(&sim_dir).expect("mkdir");
    std::fs::create_dir_all(&export).expect("mkdir");
    let runs = sim_dir.join("runs.csv");
    std::os::unix::fs::symlink(&null, &runs).expect("link");
    let summary = sim_dir.join("summary.md");
    std::os::unix::fs::symlink(&full, &summary).expect("link");
    let scenario = device(&export, "random_n0.000_o0.00_r000.csv", false).expect("mknod");
    let out = swarmpose(
        &[
            "simulate",
            "--out",
            s(&sim_dir),
            "--export",
            s(&export),
            "--runs",
            "1",
            "--noise",
            "0",
            "--fractions",
            "0",
        ],
        None,
    );
    expect(
        &out,
        1,
        &format!(
            "swarmpose: error: cannot write {}: No space left on device",
            s(&summary)
        ),
    );
    assert!(is_link(&runs) && is_link(&summary) && is_char_device(&scenario));
    // odometry --out: a streamed file and a file written whole that are devices.
    let odo = tmp.0.join("odo");
    std::fs::create_dir_all(&odo).expect("mkdir");
    let frames = odo.join("frames.csv");
    std::os::unix::fs::symlink(&null, &frames).expect("link");
    let plot = odo.join("trajectory.png");
    std::os::unix::fs::symlink(&full, &plot).expect("link");
    let out = Command::new(env!("CARGO_BIN_EXE_swarmpose"))
        .args(["odometry", "--out", s(&odo), "--quiet"])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .output()
        .expect("run");
    no_space(&out, &plot);
    assert!(is_link(&frames) && is_link(&plot));
    assert!(is_char_device(&full) && is_char_device(&null));
    for dir in [&tmp.0, &sim_dir, &export, &odo] {
        assert!(temporaries(dir).is_empty(), "{:?}", temporaries(dir));
    }
}
