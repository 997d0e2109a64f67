//! Self-calibration decisions on rigs whose error is known: the rendered synthetic street
//! with an exact rig, a right camera whose principal point is 1 px off, and a right
//! camera yawed by 0.004 rad (on these three, whose right focal length is exact, no frame
//! uses the linear term), a right camera whose focal length is 2 px long (the linear term
//! found within 10 %); the exact rig creeping 5 cm a frame; and, on synthetic
//! feature streams, how often an exact rig
//! gets a correction it does not need (the margin's false alarms).

use swarmpose_datasets::StereoSequence;

use swarmpose_odometry::{CorrectionModel, OdometryConfig};
use swarmpose_runs::synthetic::features::{FeatureSequence, FeatureSequenceConfig};
use swarmpose_runs::synthetic::{RIG, RightCameraError, SyntheticSequence};

fn decide(error: RightCameraError) -> (crate::common::Run, f64) {
    let seq = SyntheticSequence::default().with_right_camera_error(error);
    let run = crate::common::run_sequence(&seq, OdometryConfig::default());
    let e = crate::common::evaluate_poses(
        run.poses(),
        swarmpose_datasets::StereoSequence::ground_truth(&seq).expect("known path"),
    );
    let drift = e.final_drift_percent.expect("a path");
    let d = &run.calibration;
    eprintln!(
        "{error:?}: {} {} (rows: yaw {:.3} px, {} offsets; rigidity {} pairs, score {:.1}); drift {drift:.3} %",
        d.model,
        d.correction,
        d.rows.rotation_px[0],
        d.rows.measurements,
        d.pairs,
        d.rigidity_score
    );
    assert_eq!(run.untracked(), 0);
    (run, drift)
}

/// Issue 30: the term linear in `x` (cause `focal`) is used in no frame of a run whose right
/// focal length is exact, whatever else is off.
fn no_frame_has_the_linear_term(run: &crate::common::Run) {
    for r in &run.results {
        assert!(
            !r.correction_model.has(CorrectionModel::FOCAL) && r.correction.linear_x_px == 0.0,
            "frame {}: {} {}",
            r.index,
            r.correction_model,
            r.correction
        );
    }
}

#[test]
fn exact_rig_gets_no_correction() {
    let (run, drift) = decide(RightCameraError::default());
    assert_eq!(run.calibration.model, CorrectionModel::NONE);
    assert!(run.calibration.correction.is_none());
    no_frame_has_the_linear_term(&run);
    assert!(drift <= 0.1, "drift {drift} %");
}

/// An exact rig creeping forward 5 cm a frame: no frame gets a horizontal correction by
/// rigidity. Each pair moves the features by less than a pixel, where the front end's own
/// sub-pixel errors bend the pair like a disparity offset; such pairs add no rigidity
/// evidence (before they did, a -0.7 px offset was switched on and off from frame 9 on).
/// The rows (one frame each, no motion needed) see a small pattern of the rendered street
/// in frames 3-6 (a yaw of 0.2-0.3 px, held-out scores 13-18 against the margin of 10):
/// applied by the fraction its score earns, it moves no disparity by more than 0.3 px, and
/// the rig ends with no correction.
#[test]
fn exact_rig_creeping_gets_no_correction() {
    let seq = SyntheticSequence::new(24, 0.05, 0.0);
    let run = crate::common::run_sequence(&seq, OdometryConfig::default());
    assert_eq!(run.untracked(), 0);
    let x_edge = (RIG.cx + 0.5) / RIG.fx;
    let y_edge = (RIG.cy + 0.5) / RIG.fy;
    for r in &run.results {
        let horizontal = CorrectionModel::PRINCIPAL_POINT
            .with(CorrectionModel::FOCAL)
            .with(CorrectionModel::FOCAL_LENGTH);
        assert_eq!(
            r.correction_model.0 & horizontal.0,
            0,
            "frame {}: {}",
            r.index,
            r.correction_model
        );
        let worst = [(x_edge, y_edge), (0.0, 0.0), (x_edge, 0.0), (0.0, y_edge)]
            .iter()
            .map(|&(x, y)| r.correction.at_normalised(x, y).abs())
            .fold(0.0, f64::max);
        assert!(worst <= 0.3, "frame {}: {}", r.index, r.correction);
    }
    assert_eq!(run.calibration.model, CorrectionModel::NONE);
}

#[test]
fn principal_point_offset_gets_a_constant() {
    let (run, drift) = decide(RightCameraError {
        principal_point_px: 1.0,
        ..RightCameraError::default()
    });
    let d = &run.calibration;
    assert_eq!(d.model, CorrectionModel::PRINCIPAL_POINT);
    assert!(
        (d.correction.offset_px - 1.0).abs() <= 0.1,
        "{}",
        d.correction
    );
    assert_eq!(d.correction.quadratic_px, 0.0);
    no_frame_has_the_linear_term(&run);
    assert!(drift <= 0.2, "drift {drift} %");
}

#[test]
fn yaw_gets_the_quadratic_term() {
    let yaw = 0.004;
    let (run, drift) = decide(RightCameraError {
        yaw_rad: yaw,
        ..RightCameraError::default()
    });
    let d = &run.calibration;
    assert!(d.model.has(CorrectionModel::YAW), "{}", d.model);
    // δ = −f ψ (1 + x²).
    let expected = -RIG.fx * yaw;
    let q = d.correction.quadratic_px;
    assert!(
        ((q - expected) / expected).abs() <= 0.1,
        "quadratic {q:.3} px, expected {expected:.3} px"
    );
    no_frame_has_the_linear_term(&run);
    assert!(drift <= 0.5, "drift {drift} %");
}

/// A right camera whose focal length is 2 px (0.44 %) longer than the calibration's:
/// disparities are short by `2 px · x`, and the term linear in `x` (cause `focal`, a
/// default candidate) is found within 10 %: 0.97, 2.03, 3.98 and -1.99 px for 1, 2, 4 and
/// -2 px. (Its rows are scaled too, by `focal_px · y`; before the stereo refinement
/// aligned the rows as well, that pulled the disparities and the term came out 10-14 %
/// short.)
#[test]
fn right_focal_length_gets_the_linear_term() {
    let focal_px = 2.0;
    let (run, drift) = decide(RightCameraError {
        focal_px,
        ..RightCameraError::default()
    });
    let d = &run.calibration;
    assert!(d.model.has(CorrectionModel::FOCAL), "{}", d.model);
    let l = d.correction.linear_x_px;
    assert!(
        ((l - focal_px) / focal_px).abs() <= 0.1,
        "linear term {l:.3} px, expected {focal_px:.3} px"
    );
    assert!(drift <= 0.2, "drift {drift} %");
}

/// The rendered street seen by cameras whose focal length is 2 % longer than the
/// calibration's (and the camera turns 1 degree a frame): with the focal length among the
/// causes, it is chosen and found within 10 %, and the path is right; on the exact rig the
/// same candidates choose nothing.
#[test]
fn focal_length_error_gets_the_focal_length() {
    let config = OdometryConfig {
        selfcal: swarmpose_odometry::SelfCalConfig {
            candidates: CorrectionModel::DEFAULT_CANDIDATES.with(CorrectionModel::FOCAL_LENGTH),
            ..swarmpose_odometry::SelfCalConfig::default()
        },
        ..OdometryConfig::default()
    };
    let run_with = |scale: f64| {
        let seq = SyntheticSequence::default().with_focal_error(scale);
        let run = crate::common::run_sequence(&seq, config.clone());
        let e = crate::common::evaluate_poses(
            run.poses(),
            swarmpose_datasets::StereoSequence::ground_truth(&seq).expect("known path"),
        );
        (run, e)
    };
    let (run, e) = run_with(1.02);
    let d = &run.calibration;
    let expected = 0.02 * RIG.fx;
    eprintln!(
        "focal x 1.02: {} {} focal {:+.3} px (expected {expected:+.3}); drift {:?} %",
        d.model, d.correction, d.focal_px, e.final_drift_percent
    );
    assert!(d.model.has(CorrectionModel::FOCAL_LENGTH), "{}", d.model);
    assert!(
        ((d.focal_px - expected) / expected).abs() <= 0.1,
        "focal {:.3} px, expected {expected:.3} px",
        d.focal_px
    );
    let (exact, _) = run_with(1.0);
    assert_eq!(exact.calibration.model, CorrectionModel::NONE);
    assert_eq!(exact.calibration.focal_px, 0.0);
}

/// 24 feature streams of 25 frames each from an exact rig: none gets a correction.
#[test]
fn exact_rigs_rarely_get_a_correction() {
    let mut corrected = Vec::new();
    for seed in 0..24u64 {
        let seq = FeatureSequence::new(FeatureSequenceConfig {
            seed: 100 + seed,
            landmarks_per_cell: 20,
            ..FeatureSequenceConfig::default()
        });
        let mut tracker = seq.tracker(OdometryConfig::default());
        crate::common::stream(&seq, &mut tracker, 25, |_, _| {});
        let d = tracker.calibration();
        if d.model != CorrectionModel::NONE {
            corrected.push((seed, d.model, d.correction));
        }
    }
    assert!(
        corrected.is_empty(),
        "corrections on exact rigs: {corrected:?}"
    );
}

/// A camera that does not move says nothing about a principal point: even with a 1 px
/// offset injected, no constant is fitted on nothing; the rows still see a yaw.
#[test]
fn a_still_camera_gets_no_principal_point() {
    for (offset, yaw) in [(1.0, 0.0), (1.0, 1.5)] {
        let seq = FeatureSequence::new(FeatureSequenceConfig {
            step_m: 0.0,
            principal_point_px: offset,
            f_yaw_px: yaw,
            landmarks_per_cell: 20,
            ..FeatureSequenceConfig::default()
        });
        let mut tracker = seq.tracker(OdometryConfig::default());
        crate::common::stream(&seq, &mut tracker, 20, |_, r| {
            assert!(r.status.is_tracked() || r.index == 0)
        });
        let d = tracker.calibration();
        assert!(
            !d.model.has(CorrectionModel::PRINCIPAL_POINT),
            "{} {}",
            d.model,
            d.correction
        );
        assert_eq!(d.model.has(CorrectionModel::YAW), yaw != 0.0, "{}", d.model);
    }
}

/// A straight rendered drive (36 frames of 1 m) with an exact rig. A constant offset
/// passes the held-out margin by a hair for a few frames there; applied in full it jumped
/// from 0 to 0.09 px and back, and the window rescaled its 10 m of keyframes by as much:
/// the newest pose moved 50 mm along the track, and the aligned ATE was 16 mm. Weighted
/// by its evidence beyond the margin (`selfcal::applied_fraction`), the correction stays
/// small and the path smooth.
#[test]
fn a_correction_chosen_by_a_hair_is_applied_by_a_fraction() {
    let seq = SyntheticSequence::new(36, 1.0, 0.0);
    let r = crate::common::run_sequence(&seq, OdometryConfig::default());
    let e = crate::common::evaluate_poses(r.poses(), seq.ground_truth().expect("known path"));
    let offsets: Vec<f64> = r.results.iter().map(|f| f.correction.offset_px).collect();
    let largest_step = offsets
        .windows(2)
        .map(|w| (w[1] - w[0]).abs())
        .fold(0.0, f64::max);
    eprintln!(
        "straight 36 m: ATE {:.4} m, drift {:.3} %, offsets applied {offsets:.3?}",
        e.ate_aligned.rmse,
        e.final_drift_percent.unwrap_or(f64::NAN)
    );
    assert_eq!(r.untracked(), 0);
    assert!(largest_step < 0.05, "offset jumped by {largest_step:.3} px");
    assert!(
        e.ate_aligned.rmse < 0.010,
        "ATE {:.4} m",
        e.ate_aligned.rmse
    );
}

/// Issue 30: a right camera whose principal point is 1 px off, on the rendered street (20
/// frames): the correction converges from nothing to about 1 px, changing on most frames.
/// What is compared (`common::online_against_smoothed`): per frame, the online step length
/// `|t_k − t_{k−1}|` (the poses as given out) over the smoothed trajectory's step between
/// the same frames (each frame's last pose in the window), minus one. With each measurement
/// keeping the correction of its own frame (`WindowConfig::correction_per_frame`), no step
/// differs by more than 1 %; by default the window re-solves its keyframes under every new
/// correction and the online steps jump by more.
#[test]
fn a_converging_correction_moves_no_online_step_by_more_than_a_percent() {
    let seq = SyntheticSequence::default().with_right_camera_error(RightCameraError {
        principal_point_px: 1.0,
        ..RightCameraError::default()
    });
    let truth = seq.ground_truth().expect("known path");
    let run_with = |correction_per_frame: bool| {
        let mut config = OdometryConfig::default();
        config.window.correction_per_frame = correction_per_frame;
        let run = crate::common::run_sequence(&seq, config);
        let applied: Vec<f64> = run.results.iter().map(|r| r.correction.offset_px).collect();
        let rows = crate::common::online_against_smoothed(&run);
        let worst = rows.iter().fold(0.0, |w: f64, x| w.max(x.2.abs()));
        let e = crate::common::evaluate_poses(run.poses(), truth);
        eprintln!(
            "correction_per_frame {correction_per_frame}: offsets applied {applied:.3?}; \
             worst online / smoothed step {:.3} % over {} frames; drift {:.3} %",
            100.0 * worst,
            rows.len(),
            e.final_drift_percent.unwrap_or(f64::NAN)
        );
        assert_eq!(run.untracked(), 0);
        assert_eq!(rows.len(), applied.len() - 1, "a step was left out");
        let changes = applied.windows(2).filter(|w| w[1] != w[0]).count();
        assert!(
            changes >= 10,
            "the correction changed on {changes} frames only"
        );
        let decided = run.calibration.correction.offset_px;
        assert!(
            (decided - 1.0).abs() <= 0.1,
            "offset decided {decided:.3} px"
        );
        worst
    };
    let worst = run_with(true);
    assert!(
        worst <= crate::common::CALIBRATION_STEP_BAR,
        "an online step differs from the smoothed one by {:.2} %",
        100.0 * worst
    );
    let by_default = run_with(false);
    assert!(
        by_default > crate::common::CALIBRATION_STEP_BAR,
        "by default the worst step differs by {:.2} % only",
        100.0 * by_default
    );
}
