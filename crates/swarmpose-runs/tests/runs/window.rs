//! The sliding window of keyframes ([`swarmpose_odometry::window`]) side by side with the
//! frame-to-frame engine on every shared real sequence, and the same trajectory with one
//! and with two threads.

use swarmpose_odometry::{Odometry, OdometryConfig};
use swarmpose_runs::batch::{camera_of, collect, run_sequence_two_threads};
use swarmpose_runs::synthetic::SyntheticSequence;

/// The OpenCV PnP peer's aligned ATE RMS on kitti_vo_seq2, metres
/// (`tools/peers/peer_table.py`, the peer table of `crates/swarmpose-odometry/RESULTS.md`).
const PEER_ATE_ALIGNED_M: f64 = 0.535;

fn with_window(keyframes: usize) -> OdometryConfig {
    OdometryConfig::default().with_window(keyframes)
}

/// kitti_vo_seq2: a window of 10 keyframes ends closer to the ground truth than frame to
/// frame (its aligned ATE is held to a bound: frame to frame's is lower on this clip).
#[test]
fn window_beats_frame_to_frame_on_kitti() {
    let name = "kitti_vo_seq2";
    let Some(f2f) = crate::common::shared_run(name, with_window(0)) else {
        return;
    };
    let win = crate::common::shared_run(name, with_window(10)).expect("present");
    let (a, b) = (
        crate::common::evaluate_run(name, &f2f),
        crate::common::evaluate_run(name, &win),
    );
    let (da, db) = (
        a.final_drift_percent.expect("a path"),
        b.final_drift_percent.expect("a path"),
    );
    eprintln!(
        "{name}: frame to frame drift {da:.3} %, ATE {:.4} m, eq. (20) {:.5}; window of 10: \
         drift {db:.3} %, ATE {:.4} m, eq. (20) {:.5}",
        a.ate_aligned.rmse, a.eq20_rms, b.ate_aligned.rmse, b.eq20_rms
    );
    assert_eq!(win.untracked(), 0);
    assert!(
        db < da,
        "drift {db:.3} % with the window, {da:.3} % without"
    );
    // The aligned ATE: lower with the window until the stereo refinement aligned the rows
    // too (0.051 against 0.077 m); since then frame to frame is the lower on this clip
    // (0.032 against 0.044 m), though not on average over its exact variants
    // (RESULTS.md, "Since 83b13d3"). Held to the OpenCV PnP peer's on this clip.
    assert!(
        b.ate_aligned.rmse < PEER_ATE_ALIGNED_M,
        "ATE {:.4} m with the window, the peer's {PEER_ATE_ALIGNED_M} m",
        b.ate_aligned.rmse
    );
    assert!(b.eq20_rms <= 0.0011, "RMS eq. (20) {:.5}", b.eq20_rms);
}

/// Karlsruhe: the ATE after alignment onto the INS is lower with the window.
#[test]
fn window_beats_frame_to_frame_on_karlsruhe() {
    let name = "karlsruhe_2010_03_09_drive_0023";
    let Some(dir) = crate::common::dataset(name) else {
        return;
    };
    let f2f = crate::common::shared_run(name, with_window(0)).expect("present");
    let win = crate::common::shared_run(name, with_window(10)).expect("present");
    let a = crate::common::karlsruhe_ate_percent(&dir, &f2f);
    let b = crate::common::karlsruhe_ate_percent(&dir, &win);
    eprintln!("{name}: ATE frame to frame {a:.3} %, window of 10 {b:.3} % of the path");
    // Frames 37-38 are held at constant velocity (tests/runs/karlsruhe.rs): the window holds no
    // more frames at constant velocity than frame to frame, whose pair measurement it
    // starts from.
    assert!(
        win.untracked() <= f2f.untracked(),
        "{} untracked frames with the window, {} without",
        win.untracked(),
        f2f.untracked()
    );
    assert!(b < a, "ATE {b:.3} % with the window, {a:.3} % without");
}

/// The still EuRoC clip: with the window the camera stays within 3 mm of where it started;
/// no frame moves enough to be a keyframe (one loses enough tracks), every frame is
/// measured from the first, and the estimate wanders no farther from its start than frame
/// to frame's (which adds the noise of every pair). The ground truth (Vicon) itself moves
/// up to 2.6 mm here (PROVENANCE.md), so the estimate is compared with the start, not
/// with the ground truth. The farthest excursion over the clip, not the end point: a
/// random walk's end can come back by chance (with the exposure-blind alignment of
/// 2026-11-25 frame to frame ended 0.09 mm from its start, having been 0.32 mm away; the
/// window ended 0.25 mm away, at most 0.26 mm).
#[test]
fn window_keeps_a_still_camera_still() {
    let name = "euroc_v1_01_easy_micro";
    let Some(win) = crate::common::shared_run(name, with_window(10)) else {
        return;
    };
    let f2f = crate::common::shared_run(name, with_window(0)).expect("present");
    let farthest = |r: &crate::common::Run| {
        r.poses()
            .iter()
            .map(|p| p.translation.vector.norm())
            .fold(0.0, f64::max)
    };
    let end = |r: &crate::common::Run| {
        r.poses()
            .last()
            .map_or(0.0, |p| p.translation.vector.norm())
    };
    let (worst, worst_f2f) = (farthest(&win), farthest(&f2f));
    eprintln!(
        "{name}: window of 10, farthest from the start {:.2} mm, ends {:.2} mm from it; \
         frame to frame {:.2} mm and {:.2} mm",
        1e3 * worst,
        1e3 * end(&win),
        1e3 * worst_f2f,
        1e3 * end(&f2f)
    );
    assert_eq!(win.untracked(), 0);
    assert!(worst <= 0.003, "{worst} m");
    for r in &win.results[1..] {
        assert_eq!(r.reference, Some(0), "frame {}", r.index);
    }
    // Hardly any frame is a keyframe (one, frame 8, by the track rule when this was
    // written: fewer than half of its tracks were in frame 0).
    let keyframes = win.results.iter().filter(|r| r.keyframe).count();
    assert!(keyframes <= 3, "{keyframes} keyframes");
    // Frame to frame, every frame is measured from the previous one.
    assert!(f2f.results.iter().all(|r| r.keyframe));
    assert!(worst <= worst_f2f, "{worst} m against {worst_f2f} m");
}

/// One thread and two threads give the same trajectory with the window on.
#[test]
fn window_gives_the_same_trajectory_with_two_threads() {
    let seq = SyntheticSequence::default();
    let mut one = Odometry::new(camera_of(&seq), with_window(10)).expect("engine");
    let a = collect(&seq, &mut one, 0.1).expect("one thread");
    let mut two = Odometry::new(camera_of(&seq), with_window(10)).expect("engine");
    let mut b = Vec::new();
    run_sequence_two_threads(&seq, &mut two, 0.1, &mut |r| {
        b.push(r.clone());
        std::ops::ControlFlow::Continue(())
    })
    .expect("two threads");
    assert_eq!(a.len(), b.len());
    let x_covariance =
        |r: &swarmpose_odometry::FrameResult| (r.reference, r.measured_motion, r.covariance);
    for (x, y) in a.iter().zip(&b) {
        assert_eq!(x.pose, y.pose, "frame {}", x.index);
        assert_eq!(x.status, y.status, "frame {}", x.index);
    }
    // From the third frame (index 2) on the pose is the window's, measured from its oldest
    // keyframe (up to 9 frames back), with the window's covariance; before, the pair's.
    assert_eq!(a[1].reference, Some(0));
    assert!(a[1].covariance.is_some());
    for (k, r) in a.iter().enumerate().skip(2) {
        assert_eq!(r.reference, Some(k.saturating_sub(9)), "frame {k}");
        assert!(r.covariance.is_some(), "frame {k}");
        assert_eq!(x_covariance(&a[k]), x_covariance(&b[k]), "frame {k}");
    }
    let e = crate::common::evaluate_poses(
        a.iter().map(|r| r.pose).collect(),
        swarmpose_datasets::StereoSequence::ground_truth(&seq).expect("known path"),
    );
    let drift = e.final_drift_percent.expect("a path");
    eprintln!("synthetic, window of 10: drift {drift:.3} %");
    assert!(drift <= 0.1, "{drift} %");
}

/// Each tracked frame carries the window's current poses of the frames it holds: oldest
/// first, at most K of them, this frame last and equal to its online pose; earlier frames
/// revised (the smoothed trajectory of `swarmpose odometry`). The smoothed built-in street
/// is no farther from the truth than the online one.
#[test]
fn window_poses_are_given_with_each_frame() {
    let seq = SyntheticSequence::default();
    let mut odo = Odometry::new(camera_of(&seq), with_window(10)).expect("engine");
    let results = collect(&seq, &mut odo, 0.1).expect("odometry");
    let mut smoothed: Vec<_> = results.iter().map(|r| r.pose).collect();
    let mut revised = 0;
    for r in results.iter().skip(2) {
        let w = &r.window_poses;
        assert!(
            !w.is_empty() && w.len() <= 10,
            "frame {}: {} poses",
            r.index,
            w.len()
        );
        assert!(w.windows(2).all(|p| p[0].0 < p[1].0), "frame {}", r.index);
        let (last, pose) = w[w.len() - 1];
        assert_eq!(last, r.index);
        assert!((pose.translation.vector - r.pose.translation.vector).norm() < 1e-9);
        for (i, p) in w {
            if (p.translation.vector - smoothed[*i].translation.vector).norm() > 1e-9 {
                revised += 1;
            }
            smoothed[*i] = *p;
        }
    }
    assert!(revised > 0, "no earlier pose was revised");
    let gt = swarmpose_datasets::StereoSequence::ground_truth(&seq).expect("known path");
    let online = crate::common::evaluate_poses(results.iter().map(|r| r.pose).collect(), gt);
    let fixed_lag = crate::common::evaluate_poses(smoothed, gt);
    eprintln!(
        "built-in street: ATE aligned {:.4} m online, {:.4} m smoothed",
        online.ate_aligned.rmse, fixed_lag.ate_aligned.rmse
    );
    assert!(fixed_lag.ate_aligned.rmse <= online.ate_aligned.rmse);
}
