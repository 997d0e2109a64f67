//! `swarmpose odometry --split-check` on the still EuRoC clip: `split_check.csv` holds one
//! row per tracked pair with the header's fields, and the summary gives its mean NEES.

use crate::common::{TempDir, assert_success, shared_dataset, swarmpose};

#[test]
fn split_check_writes_its_rows_and_summary() {
    let Some(dir) = shared_dataset("euroc_v1_01_easy_micro") else {
        return;
    };
    let tmp = TempDir::new("odo-split");
    let out_dir = tmp.0.join("out");
    let path = |p: &std::path::Path| p.to_str().expect("utf-8 path").to_owned();
    let (d, o) = (path(&dir), path(&out_dir));
    let out = swarmpose(
        &[
            "odometry",
            &d,
            "--out",
            &o,
            "--quiet",
            "--window",
            "0",
            "--split-check",
        ],
        None,
    );
    assert_success(&out);
    let summary = String::from_utf8(out.stdout).expect("utf-8");
    let line = summary
        .lines()
        .find(|l| l.starts_with("split-feature check: mean NEES"))
        .expect("the summary's split-feature line");
    eprintln!("{line}");
    let csv = std::fs::read_to_string(out_dir.join("split_check.csv")).expect("split_check.csv");
    let rows: Vec<&str> = csv.lines().filter(|l| !l.starts_with('#')).collect();
    let fields = rows[0].split(',').count();
    assert_eq!(rows[0].split(',').next(), Some("frame"));
    assert_eq!(rows.len(), 30, "a header and 29 pairs");
    for r in &rows[1..] {
        assert_eq!(r.split(',').count(), fields, "{r}");
        let nees: f64 = r
            .split(',')
            .nth(1)
            .expect("nees")
            .parse()
            .expect("a number");
        assert!(nees.is_finite() && nees >= 0.0, "{r}");
    }
}
