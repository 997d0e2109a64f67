//! The two-thread mode (front end of frame k + 1 beside the back end of frame k) gives
//! the same results as one thread, stops where one thread stops, and names the frame
//! that broke the stream.

use std::ops::ControlFlow;

use swarmpose_datasets::{StereoSequence, open};
use swarmpose_odometry::{FrameResult, Odometry, OdometryConfig, OwnedStereoFrame, RunEnd};
use swarmpose_runs::RunError;
use swarmpose_runs::batch::{camera_of, run_sequence, run_sequence_two_threads};
use swarmpose_runs::synthetic::SyntheticSequence;
use swarmpose_vision::image::GrayImage;

type Runner = fn(
    &dyn StereoSequence,
    &mut Odometry,
    f64,
    &mut dyn FnMut(&FrameResult) -> ControlFlow<()>,
) -> Result<RunEnd, RunError>;

fn results(
    seq: &dyn StereoSequence,
    runner: Runner,
    stop_after: usize,
) -> (Vec<FrameResult>, RunEnd) {
    results_with(seq, runner, stop_after, OdometryConfig::default())
}

fn results_with(
    seq: &dyn StereoSequence,
    runner: Runner,
    stop_after: usize,
    config: OdometryConfig,
) -> (Vec<FrameResult>, RunEnd) {
    let mut odo = Odometry::new(camera_of(seq), config).expect("engine");
    let mut out = Vec::new();
    let end = runner(seq, &mut odo, 0.1, &mut |r| {
        out.push(r.clone());
        if out.len() == stop_after {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    })
    .expect("run");
    (out, end)
}

/// Everything but the stage times, which are measured.
fn assert_same(a: &[FrameResult], b: &[FrameResult]) {
    assert_eq!(a.len(), b.len());
    for (x, y) in a.iter().zip(b) {
        assert_eq!(x.index, y.index);
        assert_eq!(x.pose, y.pose, "frame {}", x.index);
        assert_eq!(x.motion, y.motion, "frame {}", x.index);
        assert_eq!(x.covariance, y.covariance, "frame {}", x.index);
        assert_eq!(x.status, y.status, "frame {}", x.index);
        assert_eq!(x.counts, y.counts, "frame {}", x.index);
        assert_eq!(x.correction, y.correction, "frame {}", x.index);
    }
}

#[test]
fn two_threads_give_the_one_thread_trajectory() {
    let synthetic = SyntheticSequence::default();
    let mut sequences: Vec<(String, Box<dyn StereoSequence>)> =
        vec![("synthetic".into(), Box::new(synthetic))];
    if let Some(dir) = crate::common::dataset("kitti_vo_seq2") {
        sequences.push(("kitti_vo_seq2".into(), open(&dir).expect("open")));
    }
    for (name, seq) in &sequences {
        // One thread: the run the other tests share (`batch::collect`, that is
        // `run_sequence` to the end), computed here for the synthetic sequence.
        let shared = (name == "kitti_vo_seq2").then(|| crate::common::default_run(name));
        let one = match shared.flatten() {
            Some(run) => run.results.clone(),
            None => {
                let (one, end1) = results(seq.as_ref(), run_sequence, usize::MAX);
                assert!(matches!(end1, RunEnd::Finished));
                one
            }
        };
        let (two, end2) = results(seq.as_ref(), run_sequence_two_threads, usize::MAX);
        assert!(matches!(end2, RunEnd::Finished));
        assert_eq!(one.len(), seq.len(), "{name}");
        assert_same(&one, &two);
        eprintln!(
            "{name}: {} frames, identical with one and two threads",
            one.len()
        );
        // Stopped by the caller after 5 frames: both stop there.
        let (one, end1) = results(seq.as_ref(), run_sequence, 5);
        let (two, end2) = results(seq.as_ref(), run_sequence_two_threads, 5);
        assert!(matches!(end1, RunEnd::Stopped(5)) && matches!(end2, RunEnd::Stopped(5)));
        assert_same(&one, &two);
    }
}

/// Images resampled to the working size ([`OdometryConfig::max_working_pixels`],
/// [`OdometryConfig::min_working_pixels`]): the front thread halves or doubles them, with
/// the same results as one thread.
#[test]
fn two_threads_resample_as_one_thread_does() {
    let seq = SyntheticSequence::new(6, 0.8, 0.0);
    let (w, h) = seq.image_size();
    let halved = OdometryConfig {
        max_working_pixels: w * h / 4,
        min_working_pixels: 0,
        ..OdometryConfig::default()
    };
    let doubled = OdometryConfig {
        min_working_pixels: w * h + 1,
        ..OdometryConfig::default()
    };
    for config in [halved, doubled] {
        let (one, _) = results_with(&seq, run_sequence, usize::MAX, config.clone());
        let (two, _) = results_with(&seq, run_sequence_two_threads, usize::MAX, config);
        assert_eq!(one.len(), seq.len());
        assert!(one.iter().skip(1).all(|r| r.status.is_tracked()));
        assert_same(&one, &two);
    }
}

#[test]
fn a_bad_frame_stops_the_stream_and_is_named() {
    let seq = SyntheticSequence::default();
    let mut odo = Odometry::new(camera_of(&seq), OdometryConfig::default()).expect("engine");
    let frames = (0..8).map(|i| {
        let pair = seq.frame(i).map_err(RunError::from)?;
        let right = if i == 6 {
            GrayImage::new(3, 3) // not the camera's size
        } else {
            pair.right
        };
        Ok(OwnedStereoFrame {
            left: pair.left,
            right,
            timestamp_s: i as f64 * 0.1,
            load_ms: 0.0,
        })
    });
    let mut seen = 0;
    let e: RunError = odo
        .run_two_threads(frames, &mut |_| {
            seen += 1;
            ControlFlow::Continue(())
        })
        .expect_err("frame 6 is bad");
    assert_eq!(seen, 6, "frames 0-5 are given out");
    assert!(e.to_string().starts_with("frame 6: "), "{e}");
    assert!(matches!(e, RunError::AtFrame { index: 6, .. }), "{e}");
}

/// The vector kernels ([`swarmpose_vision::simd`]) compiled for the target's baseline
/// (the scalar fallback: SSE2 on x86_64) give the trajectory of their dispatched
/// compilation (AVX2 and POPCNT where the CPU has them), frame by frame, with the same
/// feature, stereo and match counts, on every shared sequence.
#[test]
fn baseline_kernels_give_the_dispatched_trajectory() {
    let mut sequences: Vec<(String, Box<dyn StereoSequence>)> =
        vec![("synthetic".into(), Box::new(SyntheticSequence::default()))];
    for name in [
        "kitti_vo_seq2",
        "karlsruhe_2010_03_09_drive_0023",
        "euroc_v1_01_easy_micro",
    ] {
        if let Some(dir) = crate::common::dataset(name) {
            sequences.push((name.into(), open(&dir).expect("open")));
        }
    }
    for (name, seq) in &sequences {
        let frames = 12;
        let (fast, _) = results(seq.as_ref(), run_sequence, frames);
        let (scalar, _) =
            swarmpose_vision::simd::baseline(|| results(seq.as_ref(), run_sequence, frames));
        assert_eq!(fast.len(), frames.min(seq.len()), "{name}");
        assert_same(&fast, &scalar);
        let features: usize = fast.iter().map(|r| r.counts.left_features).sum();
        assert!(features > 0, "{name}: no features");
        eprintln!(
            "{name}: {} frames ({features} left features), identical with the baseline kernels",
            fast.len()
        );
    }
}

/// The front thread matches each frame to the last one with enough points ahead of the
/// back end; the back end takes those matches only when they are with its reference and
/// the search is unguided. Results equal one thread's when frames in between have no
/// texture (the reference is then an earlier frame), when the engine tracked frames
/// before the run (its reference is not the run's), and with the guided search.
#[test]
fn matching_ahead_gives_one_threads_matches() {
    let seq = SyntheticSequence::new(10, 0.8, 0.0);
    let (w, h) = seq.image_size();
    let blank = |i: usize| (3..5).contains(&i);
    let frame = |i: usize| -> Result<OwnedStereoFrame, RunError> {
        let pair = seq.frame(i).map_err(RunError::from)?;
        let (left, right) = if blank(i) {
            let mut flat = GrayImage::new(w, h);
            flat.data.fill(128);
            (flat.clone(), flat)
        } else {
            (pair.left, pair.right)
        };
        Ok(OwnedStereoFrame {
            left,
            right,
            timestamp_s: i as f64 * 0.1,
            load_ms: 0.0,
        })
    };
    let mut guided = OdometryConfig::default();
    guided.orb.temporal.guided_radius_px = Some(20.0);
    let configs = [
        ("default", OdometryConfig::default()),
        ("frame to frame", OdometryConfig::default().with_window(0)),
        ("guided", guided),
    ];
    for (name, config) in configs {
        for before in [0, 2] {
            let mut one = Odometry::new(camera_of(&seq), config.clone()).expect("engine");
            let mut two = Odometry::new(camera_of(&seq), config.clone()).expect("engine");
            let mut expected = Vec::new();
            for i in 0..seq.len() {
                expected.push(track_one(&mut one, &frame(i).expect("frame")));
            }
            // The first `before` frames one at a time, the rest on two threads.
            let mut got = Vec::new();
            for i in 0..before {
                got.push(track_one(&mut two, &frame(i).expect("frame")));
            }
            let end = two
                .run_two_threads((before..seq.len()).map(frame), &mut |r| {
                    got.push(r.clone());
                    ControlFlow::Continue(())
                })
                .expect("run");
            assert!(matches!(end, RunEnd::Finished), "{name}");
            assert_same(&expected, &got);
            assert!(
                expected[3..5].iter().all(|r| !r.status.is_tracked()),
                "{name}: the blank frames are not tracked"
            );
            assert!(
                expected[5].status.is_tracked(),
                "{name}: {:?}",
                expected[5].status
            );
            if name == "frame to frame" {
                assert_eq!(
                    expected[5].reference,
                    Some(2),
                    "{name}: matched across the gap"
                );
            }
        }
    }
}

/// `frame` through `odo` on the calling thread.
fn track_one(odo: &mut Odometry, frame: &OwnedStereoFrame) -> FrameResult {
    odo.track(swarmpose_odometry::StereoInput {
        left: frame.left.view(),
        right: frame.right.view(),
        timestamp_s: frame.timestamp_s,
    })
    .expect("track")
}
