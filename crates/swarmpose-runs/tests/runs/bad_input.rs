//! Bad input to the engine: frames of another size than the camera, an empty image,
//! left and right of different sizes, left and right exchanged, a buffer shorter than its
//! size says, timestamps
//! that do not increase, a camera that is not one, and a frame with no texture. Each is
//! a clear error (the engine's state unchanged) or a visible status, never a panic; the
//! engine goes on with the next good frames.

use swarmpose_datasets::StereoSequence;
use swarmpose_odometry::{Odometry, OdometryConfig, Status, StereoCamera, StereoInput};
use swarmpose_runs::batch::camera_of;
use swarmpose_runs::synthetic::SyntheticSequence;
use swarmpose_vision::features::GrayView;
use swarmpose_vision::image::GrayImage;

fn input<'a>(left: &'a GrayImage, right: &'a GrayImage, t: f64) -> StereoInput<'a> {
    StereoInput {
        left: left.view(),
        right: right.view(),
        timestamp_s: t,
    }
}

#[test]
fn bad_frames_are_refused_and_the_engine_goes_on() {
    let seq = SyntheticSequence::new(8, 0.5, 0.01);
    let mut odo = Odometry::new(camera_of(&seq), OdometryConfig::default()).expect("engine");
    let f0 = seq.frame(0).expect("frame");
    let r = odo.track(input(&f0.left, &f0.right, 0.0)).expect("first");
    assert_eq!(r.status, Status::First);

    let small = GrayImage::new(100, 80);
    let empty = GrayImage::new(0, 0);
    let f1 = seq.frame(1).expect("frame");
    let cases: [(StereoInput<'_>, &str); 6] = [
        (
            input(&f1.right, &f1.left, 0.1),
            "the left and right images look exchanged",
        ),
        (
            input(&small, &small, 0.1),
            "the left image is 100x80, but the camera's images are 480x288",
        ),
        (input(&f1.left, &small, 0.1), "the right image is 100x80"),
        (input(&empty, &f1.right, 0.1), "the left image is empty"),
        (
            input(&f1.left, &f1.right, 0.0),
            "does not come after the previous frame's",
        ),
        (
            input(&f1.left, &f1.right, f64::NAN),
            "is not a finite number of seconds",
        ),
    ];
    for (frame, expected) in cases {
        let e = odo.track(frame).expect_err("refused").to_string();
        assert!(e.contains(expected), "{e}");
    }
    let short = GrayView {
        width: 480,
        height: 288,
        data: &f1.left.data[..1000],
    };
    let e = odo
        .track(StereoInput {
            left: short,
            right: f1.right.view(),
            timestamp_s: 0.1,
        })
        .expect_err("short buffer")
        .to_string();
    assert!(e.contains("holds 1000 values"), "{e}");
    // The state is unchanged: the next good frame is frame 1, tracked.
    let r = odo.track(input(&f1.left, &f1.right, 0.1)).expect("frame 1");
    assert_eq!(r.index, 1);
    assert!(r.status.is_tracked(), "{:?}", r.status);
    // A frame with no texture is marked, and tracking resumes after it.
    let black = GrayImage::new(480, 288);
    let r = odo.track(input(&black, &black, 0.2)).expect("black frame");
    assert!(
        matches!(r.status, Status::ConstantVelocity(_)),
        "{:?}",
        r.status
    );
    for k in 3..8 {
        let f = seq.frame(k).expect("frame");
        let r = odo
            .track(input(&f.left, &f.right, 0.1 * k as f64))
            .expect("frame");
        assert!(r.status.is_tracked(), "frame {k}: {:?}", r.status);
        let truth = seq.ground_truth().expect("known")[k];
        let err = (r.pose.translation.vector - truth.translation.vector).norm();
        assert!(err < 0.05, "frame {k}: {err} m off");
    }
}

#[test]
fn a_camera_that_is_not_one_is_refused() {
    let good = camera_of(&SyntheticSequence::new(2, 0.5, 0.0));
    let bad = [
        StereoCamera { width: 0, ..good },
        StereoCamera {
            rig: swarmpose_vision::stereo::RectifiedStereo {
                baseline_m: 0.0,
                ..good.rig
            },
            ..good
        },
        StereoCamera {
            rig: swarmpose_vision::stereo::RectifiedStereo {
                fx: f64::NAN,
                ..good.rig
            },
            ..good
        },
    ];
    for camera in bad {
        let e = Odometry::new(camera, OdometryConfig::default())
            .err()
            .expect("refused")
            .to_string();
        assert!(e.starts_with("camera:"), "{e}");
    }
}

#[test]
fn fewer_than_three_inliers_is_refused_not_raised() {
    // Fewer than three points fix no motion: the engine used to take 0, 1 or 2 as 3
    // without a word (the CLI and Python refuse them with the same message).
    let camera = camera_of(&SyntheticSequence::new(2, 0.5, 0.0));
    for n in [0, 1, 2] {
        let config = OdometryConfig {
            min_inliers: n,
            ..OdometryConfig::default()
        };
        let e = Odometry::new(camera, config).err().expect("refused");
        assert!(
            matches!(e, swarmpose_odometry::OdometryError::Config { .. }),
            "{e}"
        );
        assert_eq!(
            e.to_string(),
            format!("min_inliers {n}: at least 3 are needed for a motion")
        );
    }
    let three = OdometryConfig {
        min_inliers: swarmpose_odometry::MIN_INLIERS,
        ..OdometryConfig::default()
    };
    assert!(Odometry::new(camera, three).is_ok());
}

#[test]
fn a_guided_search_radius_that_is_not_a_distance_is_refused() {
    let camera = camera_of(&SyntheticSequence::new(2, 0.5, 0.0));
    let with = |radius: Option<f32>, ratio: f32| {
        let mut config = OdometryConfig::default();
        config.orb.temporal.guided_radius_px = radius;
        config.orb.temporal.guided_min_ratio = ratio;
        Odometry::new(camera, config)
    };
    for (radius, ratio) in [
        (Some(0.0), 0.75),
        (Some(-5.0), 0.75),
        (Some(f32::NAN), 0.75),
        (Some(20.0), -0.1),
        (Some(20.0), f32::INFINITY),
    ] {
        let e = with(radius, ratio).err().expect("refused");
        assert!(
            matches!(e, swarmpose_odometry::OdometryError::Config { .. }),
            "{e}"
        );
    }
    assert!(with(Some(20.0), 0.75).is_ok());
    assert!(with(None, 0.75).is_ok());
}
