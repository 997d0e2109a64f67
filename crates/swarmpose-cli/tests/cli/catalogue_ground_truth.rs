//! Ground truth validated (issue 29, cause 9): a EuRoC ground truth with a quaternion of
//! norm 0 gave NaN poses and metrics with exit 0; one that misses frames was dropped
//! without a word. Now the first is refused naming the line, the second said.

use crate::catalogue::{corr, euroc, expect, s, succeeded};
use crate::common::TempDir;

#[test]
fn euroc_ground_truth_with_a_zero_quaternion_or_missing_frames() {
    let tmp = TempDir::new("cat-gt");
    let Some(seq) = euroc(&tmp.0, "e", 6) else {
        return;
    };
    let Some(shared) = swarmpose_testdata::dataset_for_test("euroc_v1_01_easy_micro") else {
        return;
    };
    let rel = "mav0/state_groundtruth_estimate0/data.csv";
    let text = std::fs::read_to_string(shared.join(rel)).expect("ground truth");
    let gt = seq.join(rel);
    std::fs::create_dir_all(gt.parent().expect("folder")).expect("mkdir");
    let frames = std::fs::read_to_string(seq.join("mav0/cam0/data.csv")).expect("list");
    let stamp = |k: usize| -> i64 {
        let row = frames.lines().filter(|l| !l.starts_with('#')).nth(k);
        row.and_then(|r| r.split(',').next()?.parse().ok())
            .expect("timestamp")
    };
    // The poses within 10 ms of frame 3 left out: the ground truth misses a frame.
    let gap: Vec<&str> = text
        .lines()
        .filter(|l| {
            let t: Option<i64> = l.split(',').next().and_then(|t| t.parse().ok());
            t.is_none_or(|t| (t - stamp(3)).abs() > 10_000_000)
        })
        .collect();
    std::fs::write(&gt, gap.join("\n") + "\n").expect("write");
    let out = corr(&tmp, &seq, &[]);
    succeeded(&out);
    let stderr = String::from_utf8_lossy(&out.stderr);
    let warning = format!(
        "swarmpose: warning: {}: no pose within 5 ms of 1 of the 6 frames (the first: frame 3, \
         timestamp {} ns): the ground truth is not used",
        s(&gt),
        stamp(3)
    );
    assert!(stderr.contains(&warning), "{stderr}");
    // A quaternion of norm 0 on line 3.
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let fields: Vec<&str> = lines[2].split(',').collect();
    lines[2] = format!(
        "{},{},{},{},0,0,0,0",
        fields[0], fields[1], fields[2], fields[3]
    );
    std::fs::write(&gt, lines.join("\n") + "\n").expect("write");
    expect(
        &corr(&tmp, &seq, &[]),
        2,
        &format!(
            "swarmpose: error: {}:3: the quaternion (q_w, q_x, q_y, q_z) = (0, 0, 0, 0) has \
             norm 0.000e0: a rotation's has norm 1",
            s(&gt)
        ),
    );
}
