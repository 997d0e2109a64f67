//! One output folder, one run (issue 29, cause 8): a second run into a folder in use is
//! refused (a lock), a folder an earlier version wrote without a manifest is cleaned of
//! the files a run writes, and the temporaries of a killed run are removed by the next.

use std::fs::File;

use crate::catalogue::{expect, kitti, s, succeeded};
use crate::common::{TempDir, odometry};

#[test]
fn a_folder_in_use_is_refused_and_an_earlier_run_s_leftovers_removed() {
    let tmp = TempDir::new("out-folder");
    let Some(seq) = kitti(&tmp.0, "k", 3) else {
        return;
    };
    std::fs::remove_file(seq.join("poses.txt")).expect("no ground truth");
    let out_dir = tmp.0.join("o");
    std::fs::create_dir_all(&out_dir).expect("mkdir");
    let run = || odometry(Some(&seq), &out_dir, &[]);
    // Another run holds the folder (its lock, as a running odometry holds it).
    let lock = File::create(out_dir.join(".swarmpose-lock")).expect("lock file");
    lock.try_lock().expect("lock");
    let out = run();
    expect(
        &out,
        1,
        &format!(
            "swarmpose: error: {}: cannot write: in use by another run",
            s(&out_dir)
        ),
    );
    assert!(out.stdout.is_empty(), "no frame was run");
    assert!(!out_dir.join("frames.csv").exists());
    drop(lock);
    // A folder of an earlier version (no manifest) with files this run does not write
    // (no ground truth: no evaluation), a file of the user's, and the temporaries of a
    // killed run (its process id long gone).
    let old = ["evaluation.json", "groundtruth.kitti.txt", "errors.png"];
    for name in old {
        std::fs::write(out_dir.join(name), "old").expect("write");
    }
    let temporaries = [
        ".trajectory.png.partial-99999999.png",
        ".calibration.json.partial-4242.json",
    ];
    for name in temporaries.iter().chain(&["notes.txt", ".notes.partial-x"]) {
        std::fs::write(out_dir.join(name), "x").expect("write");
    }
    let out = run();
    succeeded(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(
        stderr.contains("no .swarmpose-manifest (a folder of an earlier version): removed its")
            && old.iter().all(|n| stderr.contains(n)),
        "{stderr}"
    );
    for name in old.iter().chain(&temporaries) {
        assert!(!out_dir.join(name).exists(), "{name} removed");
    }
    for name in ["notes.txt", ".notes.partial-x", "trajectory.kitti.txt"] {
        assert!(out_dir.join(name).is_file(), "{name} kept");
    }
    // The run recorded its files (it records only names the cleaning knows, or fails).
    let manifest = std::fs::read_to_string(out_dir.join(".swarmpose-manifest")).expect("manifest");
    assert!(
        manifest.lines().count() == 11
            && manifest.contains("config.json")
            && manifest.contains("trajectory.svg")
            && manifest.contains("odometry.mcap"),
        "{manifest}"
    );
    // The lock is released with the run: the next run goes ahead.
    succeeded(&run());
}
