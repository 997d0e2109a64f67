//! `swarmpose odometry` on RGB-D ROS 2 bags written here (swarmpose-testdata's bags: a
//! colour and a depth `sensor_msgs/Image` topic with `camera_info`, from the synthetic
//! street rendered with exact depth): with the topics named (`--left COLOUR --depth
//! DEPTH`) and found, depth in `32FC1` metres and in `16UC1` millimetres, the run writes
//! the `trajectory.kitti.txt` of the TUM RGB-D folder of the same frames byte for byte.
//! Bad RGB-D input is refused in one line, exit 2, and an earlier run's outputs are kept;
//! a depth image in a wrong encoding in the middle of the bag stops the run there, its
//! frames before it kept.

use std::path::Path;

use swarmpose_runs::rgbd::RgbdSequence;
use swarmpose_testdata::bags::write_mcap;
use swarmpose_testdata::rgbd::{
    COLOUR, DEPTH, FRAMES, image as image_message, rgbd_topics, second_depth_camera, small_bag,
    stamp, tum_folder,
};

use crate::common::{TempDir, assert_success, check_error, swarmpose};

fn s(p: &Path) -> &str {
    p.to_str().expect("utf-8 path")
}

/// `swarmpose odometry INPUT --out OUT --quiet` and `options`.
fn odometry(input: &Path, out: &Path, options: &[&str]) -> std::process::Output {
    let mut args = vec!["odometry", s(input), "--out", s(out), "--quiet"];
    args.extend(options);
    swarmpose(&args, None)
}

fn trajectory(out: &Path) -> Vec<u8> {
    std::fs::read(out.join("trajectory.kitti.txt")).expect("trajectory.kitti.txt")
}

/// The TUM RGB-D folder of the synthetic street in `tmp`, and the `trajectory.kitti.txt`
/// of its run.
fn folder_run(tmp: &TempDir) -> (RgbdSequence, Vec<u8>) {
    let folder = tum_folder(&tmp.0);
    let o = odometry(folder.root(), &tmp.path("out_folder"), &[]);
    assert_success(&o);
    (folder, trajectory(&tmp.path("out_folder")))
}

#[test]
fn an_rgbd_bag_gives_the_folder_trajectory_byte_for_byte() {
    let tmp = TempDir::new("cli-rgbd-bags");
    let (folder, want) = folder_run(&tmp);
    assert_eq!(
        String::from_utf8_lossy(&want).lines().count(),
        FRAMES,
        "a pose per frame"
    );
    for encoding in ["32FC1", "16UC1"] {
        let bag = tmp.path(&format!("rgbd_{encoding}.mcap"));
        write_mcap(&bag, &rgbd_topics(&folder, encoding));
        for (how, options) in [
            ("named", vec!["--left", COLOUR, "--depth", DEPTH]),
            ("found", vec![]),
        ] {
            let out = tmp.path(&format!("out_{encoding}_{how}"));
            let o = odometry(&bag, &out, &options);
            assert_success(&o);
            assert!(
                trajectory(&out) == want,
                "{encoding}, topics {how}: the trajectory differs from the folder's"
            );
            eprintln!("{encoding}, topics {how}: trajectory.kitti.txt identical to the folder's");
        }
    }
}

#[test]
fn bad_rgbd_bags_are_refused_in_one_line_and_keep_the_outputs() {
    let tmp = TempDir::new("cli-rgbd-bad");
    let out = tmp.path("out");
    // An earlier run's outputs in the folder the bad runs are pointed at.
    let ok = small_bag(&tmp.path("ok.mcap"), "32FC1", (32, 24), &[]);
    let o = odometry(&ok, &out, &[]);
    assert!(out.join("trajectory.kitti.txt").is_file(), "{o:?}");
    let before = trajectory(&out);
    let mono = small_bag(&tmp.path("mono.mcap"), "mono8", (32, 24), &[]);
    let size = small_bag(&tmp.path("size.mcap"), "16UC1", (16, 12), &[]);
    let two = small_bag(
        &tmp.path("two.mcap"),
        "16UC1",
        (32, 24),
        &second_depth_camera(),
    );
    let cases: [(&Path, &[&str], &[&str]); 3] = [
        (
            &mono,
            &["--depth", DEPTH],
            &[DEPTH, "depth encoding 'mono8'", "16UC1", "32FC1"],
        ),
        (
            &size,
            &[],
            &["depth images of 16x12 but colour images of 32x24", DEPTH],
        ),
        (
            &two,
            &[],
            &["2 depth cameras", "--depth", "(sensor_msgs/msg/Image, 3)"],
        ),
    ];
    for (bag, options, needles) in cases {
        let o = odometry(bag, &out, options);
        let line = check_error(&o, needles);
        assert!(line.contains(s(bag)), "names the bag: {line}");
        assert_eq!(trajectory(&out), before, "{line}: the earlier outputs kept");
    }
}

#[test]
fn a_bad_depth_image_mid_bag_stops_the_run_and_keeps_its_frames() {
    let tmp = TempDir::new("cli-rgbd-cut");
    let (folder, want) = folder_run(&tmp);
    let want = String::from_utf8(want).expect("utf-8");
    // The last frame's depth in a colour encoding.
    let mut topics = rgbd_topics(&folder, "16UC1");
    let last = FRAMES - 1;
    let t = stamp(last);
    topics[2].2[last] = (t, image_message(t, "mono8", (4, 2), vec![0; 8]));
    let bag = tmp.path("bad_last.mcap");
    write_mcap(&bag, &topics);
    let out = tmp.path("out");
    let o = odometry(&bag, &out, &[]);
    let stderr = String::from_utf8_lossy(&o.stderr);
    assert_ne!(o.status.code(), Some(0), "{stderr}");
    let lines: Vec<&str> = stderr.lines().collect();
    assert_eq!(lines.len(), 1, "one line: {stderr}");
    let stopped = format!("stopped after {last} frame(s)");
    for needle in [DEPTH, "depth encoding 'mono8'", stopped.as_str(), s(&out)] {
        assert!(lines[0].contains(needle), "{needle:?} not in {stderr}");
    }
    let got = String::from_utf8(trajectory(&out)).expect("utf-8");
    assert_eq!(got.lines().count(), last, "{got}");
    assert!(want.starts_with(&got), "the kept poses are the folder's");
}
