//! TUM RGB-D input on frames of the synthetic street rendered with exact depth: the
//! trajectory follows the known path, and malformed directories give clear errors.

use std::ops::ControlFlow;

use swarmpose_eval::associate::by_index;
use swarmpose_eval::{Trajectory, evaluate};
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::{Odometry, OdometryConfig, Status};
use swarmpose_runs::batch::run_rgbd_sequence;
use swarmpose_runs::rgbd::RgbdSequence;
use swarmpose_runs::synthetic::SyntheticSequence;

fn tmp(tag: &str) -> std::path::PathBuf {
    let d = std::env::temp_dir().join(format!("swarmpose-rgbd-{tag}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).expect("tmp");
    d
}

#[test]
fn synthetic_tum_rgbd_is_followed() {
    let dir = tmp("ok");
    // 12 frames, 0.3 m and 1 degree per frame.
    SyntheticSequence::new(12, 0.3, 1f64.to_radians())
        .write_tum_rgbd(&dir)
        .expect("write");
    let seq = RgbdSequence::open(&dir).expect("open");
    assert_eq!(seq.len(), 12);
    // Frame to frame, and with the default window of 10 keyframes.
    for keyframes in [0, 10] {
        let mut odo = Odometry::builder(seq.camera().expect("camera"))
            .config(OdometryConfig::default().with_window(keyframes))
            .rgbd(RgbdNoise::default())
            .build()
            .expect("engine");
        let mut results = Vec::new();
        run_rgbd_sequence(&seq, &mut odo, &mut |r| {
            results.push(r.clone());
            ControlFlow::Continue(())
        })
        .expect("run");
        let gt = seq.ground_truth().expect("groundtruth.txt").to_vec();
        // Re-based on the first frame: the first true pose is the identity.
        assert!(gt[0].translation.vector.norm() < 1e-9);
        let poses: Vec<_> = results.iter().map(|r| r.pose).collect();
        let e = evaluate(
            &by_index(
                &Trajectory::indexed("estimate", poses),
                &Trajectory::indexed("truth", gt),
            )
            .expect("pairs"),
        )
        .expect("evaluate");
        for f in &results {
            eprintln!(
                "frame {:2}: {:4} points {:4} matches {:4} inliers {}",
                f.index,
                f.counts.stereo_points,
                f.counts.matches,
                f.counts.inliers,
                f.status.text()
            );
        }
        eprintln!(
            "rgbd, window {keyframes}: path {:.2} m, drift {:.4} m ({:.2} %), RMS eq. (20) {:.5}, ATE {:.4} m",
            e.path_length_m,
            e.final_drift_m,
            e.final_drift_percent.unwrap_or(f64::NAN),
            e.eq20_rms,
            e.ate_aligned.rmse
        );
        assert!((results[1].timestamp_s - results[0].timestamp_s - 1.0 / 30.0).abs() < 1e-5);
        assert!(
            results
                .iter()
                .all(|r| matches!(r.status, Status::First | Status::Tracked))
        );
        assert!(e.final_drift_percent.expect("3.3 m") < 2.0);
        assert!(e.eq20_rms < 0.01);
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn malformed_tum_rgbd_gives_clear_errors() {
    let dir = tmp("bad");
    std::fs::write(dir.join("rgb.txt"), "# c\n1.0 rgb/1.png\n2.0\n").expect("w");
    std::fs::write(dir.join("depth.txt"), "1.0 depth/1.png\n").expect("w");
    let e = RgbdSequence::open(&dir)
        .expect_err("truncated line")
        .to_string();
    assert!(
        e.contains("rgb.txt:3") && e.contains("timestamp filename"),
        "{e}"
    );
    std::fs::write(dir.join("rgb.txt"), "1.0 rgb/1.png\n2.0 rgb/2.png\n").expect("w");
    let e = RgbdSequence::open(&dir)
        .expect_err("no depth for 2.0")
        .to_string();
    assert!(
        e.contains("depth.txt") && e.contains("colour image 2"),
        "{e}"
    );
    std::fs::write(dir.join("depth.txt"), "1.0 depth/1.png\n2.01 depth/2.png\n").expect("w");
    std::fs::write(dir.join("groundtruth.txt"), "1.0 0 0 0 0 0 0 1\n").expect("w");
    let e = RgbdSequence::open(&dir).expect_err("gt short").to_string();
    assert!(
        e.contains("groundtruth.txt") && e.contains("frame 2"),
        "{e}"
    );
    std::fs::write(dir.join("groundtruth.txt"), "1.0 0 0 0 0 0 1\n").expect("w");
    let e = RgbdSequence::open(&dir)
        .expect_err("gt truncated")
        .to_string();
    assert!(
        e.contains("groundtruth.txt:1") && e.contains("8 numbers"),
        "{e}"
    );
    std::fs::remove_file(dir.join("groundtruth.txt")).expect("rm");
    let seq = RgbdSequence::open(&dir).expect("no ground truth is fine");
    let e = seq.frame(0).expect_err("missing png").to_string();
    assert!(e.contains("1.png"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}

/// Issue 29, cause 6: an 8-bit or colour image named as depth, a saturated depth, a
/// labelled `intrinsics.txt`.
#[test]
fn depth_images_and_intrinsics_are_checked() {
    let dir = tmp("checked");
    SyntheticSequence::new(2, 0.3, 0.0)
        .write_tum_rgbd(&dir)
        .expect("write");
    let list = std::fs::read_to_string(dir.join("depth.txt")).expect("depth.txt");
    let first = list
        .lines()
        .find(|l| !l.starts_with('#'))
        .and_then(|l| l.split_whitespace().nth(1))
        .expect("a depth image");
    let depth = dir.join(first);
    let (w, h) = image::image_dimensions(&depth).expect("size");
    // Every depth saturated (65535): no depth, not 13.107 m.
    image::ImageBuffer::<image::Luma<u16>, _>::from_pixel(w, h, image::Luma([u16::MAX]))
        .save(&depth)
        .expect("save");
    let seq = RgbdSequence::open(&dir).expect("open");
    let (_, metres) = seq.frame(0).expect("frame");
    assert!(metres.iter().all(|&z| z == 0.0));
    // An 8-bit image named as depth.
    image::GrayImage::from_pixel(w, h, image::Luma([200]))
        .save(&depth)
        .expect("save");
    let e = seq.frame(0).expect_err("8-bit").to_string();
    assert!(e.contains("is not a depth image"), "{e}");
    // A labelled intrinsics.txt.
    std::fs::write(
        dir.join("intrinsics.txt"),
        "cx 319.5 cy 239.5 fx 525 fy 525\n",
    )
    .expect("w");
    let e = RgbdSequence::open(&dir).expect_err("labelled").to_string();
    assert!(e.contains("'cx' is not a number"), "{e}");
    let _ = std::fs::remove_dir_all(&dir);
}
