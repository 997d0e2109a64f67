//! RGB-D bags (a colour and a depth `sensor_msgs/Image` topic, each with `camera_info`)
//! written here with the `mcap` crate from the synthetic street rendered with exact
//! depth, and read as the TUM RGB-D folder of the same frames is: the run on the bag
//! gives the folder run's trajectory byte for byte (depth in `32FC1` metres, the folder's
//! values; and in `16UC1` millimetres, the folder's depths being whole millimetres). Bad
//! RGB-D input is refused in one line.

mod common;

use std::ops::ControlFlow;
use std::path::Path;

use swarmpose_datasets::DepthSequence;
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::{FrameResult, Odometry, OdometryConfig, Status};
use swarmpose_ros::{Input, StereoOptions, open_input};
use swarmpose_runs::batch::{rgbd_camera, run_rgbd_sequence};
use swarmpose_runs::rgbd::RgbdSequence;
use swarmpose_testdata::bags::write_mcap;
use swarmpose_testdata::rgbd::{
    COLOUR, DEPTH, FRAMES, rgbd_topics, second_depth_camera, small_bag, tum_folder,
};

fn run(seq: &dyn DepthSequence) -> Vec<FrameResult> {
    let mut odo = Odometry::builder(rgbd_camera(seq).expect("camera"))
        .config(OdometryConfig::default())
        .rgbd(RgbdNoise::default())
        .build()
        .expect("engine");
    let mut out = Vec::new();
    run_rgbd_sequence(seq, &mut odo, &mut |r| {
        out.push(r.clone());
        ControlFlow::Continue(())
    })
    .expect("run");
    out
}

/// The bits of each pose and time of a run.
fn bits(results: &[FrameResult]) -> Vec<Vec<u64>> {
    results
        .iter()
        .map(|r| {
            let m = r.pose.to_homogeneous();
            m.iter()
                .chain(std::iter::once(&r.timestamp_s))
                .map(|x| x.to_bits())
                .collect()
        })
        .collect()
}

fn open_rgbd(path: &Path, opts: &StereoOptions) -> Box<dyn DepthSequence> {
    match open_input(path, opts)
        .unwrap_or_else(|e| panic!("{e}"))
        .input
    {
        Input::Rgbd(seq) => seq,
        Input::Stereo(_) => panic!("{}: opened as stereo", path.display()),
    }
}

#[test]
fn an_rgbd_bag_runs_as_its_folder() {
    let dir = common::scratch("rgbd_bags");
    let folder = tum_folder(&dir);
    let expected = run(&folder);
    assert_eq!(expected.len(), FRAMES);
    assert!(
        expected[1..]
            .iter()
            .all(|r| matches!(r.status, Status::Tracked)),
        "{:?}",
        expected.iter().map(|r| r.status.text()).collect::<Vec<_>>()
    );
    let moved = expected[FRAMES - 1].pose.translation.vector.norm();
    assert!(moved > 0.5, "the camera moved {moved} m");
    for encoding in ["32FC1", "16UC1"] {
        let path = dir.join(format!("rgbd_{encoding}.mcap"));
        write_mcap(&path, &rgbd_topics(&folder, encoding));
        // Found: one colour and one depth camera.
        let bag = open_rgbd(&path, &StereoOptions::default());
        assert_eq!(bag.len(), FRAMES);
        assert_eq!(bag.camera().expect("camera"), folder_camera(&folder));
        for f in 0..FRAMES {
            let (a, b) = (bag.frame(f).expect("bag"), folder.frame(f).expect("folder"));
            assert_eq!((a.gray, a.depth_m), b, "{encoding} frame {f}");
        }
        assert_eq!(bits(&run(bag.as_ref())), bits(&expected), "{encoding}");
        // Named.
        let named = StereoOptions {
            left: Some(COLOUR.to_owned()),
            depth: Some(DEPTH.to_owned()),
            ..StereoOptions::default()
        };
        assert_eq!(open_rgbd(&path, &named).len(), FRAMES);
        eprintln!("{encoding}: {FRAMES} frames, the folder's trajectory to the bit");
    }
}

fn folder_camera(folder: &RgbdSequence) -> (swarmpose_datasets::Intrinsics, (usize, usize)) {
    DepthSequence::camera(folder).expect("folder camera")
}

fn open_err(path: &Path, opts: &StereoOptions) -> String {
    let e = open_input(path, opts).expect_err("refused").to_string();
    assert!(!e.contains('\n'), "one line: {e}");
    assert!(
        e.starts_with(&path.display().to_string()),
        "names the bag: {e}"
    );
    e
}

#[test]
fn bad_rgbd_input_is_refused_in_one_line() {
    let dir = common::scratch("rgbd_bad");
    let ok = small_bag(&dir.join("ok.mcap"), "32FC1", (32, 24), &[]);
    assert_eq!(open_rgbd(&ok, &StereoOptions::default()).len(), 3);
    // The depth topic named, in a colour encoding.
    let mono = small_bag(&dir.join("mono.mcap"), "mono8", (32, 24), &[]);
    let named = StereoOptions {
        depth: Some(DEPTH.to_owned()),
        ..StereoOptions::default()
    };
    let e = open_err(&mono, &named);
    assert!(
        e.contains(DEPTH) && e.contains("depth encoding 'mono8'") && e.contains("16UC1"),
        "{e}"
    );
    // Depth and colour of different sizes.
    let small = small_bag(&dir.join("size.mcap"), "16UC1", (16, 12), &[]);
    let e = open_err(&small, &StereoOptions::default());
    assert!(
        e.contains("depth images of 16x12 but colour images of 32x24"),
        "{e}"
    );
    // Two depth cameras: ambiguous, the topics listed.
    let two = small_bag(
        &dir.join("two.mcap"),
        "16UC1",
        (32, 24),
        &second_depth_camera(),
    );
    let e = open_err(&two, &StereoOptions::default());
    assert!(
        e.contains("2 depth cameras")
            && e.contains("--depth")
            && e.contains(&format!("{DEPTH} (sensor_msgs/msg/Image, 3)")),
        "{e}"
    );
    // A depth topic and a right topic named.
    let both = StereoOptions {
        right: Some(COLOUR.to_owned()),
        depth: Some(DEPTH.to_owned()),
        ..StereoOptions::default()
    };
    let e = open_err(&ok, &both);
    assert!(e.contains("--left and --right for stereo"), "{e}");
}
