//! A rig that is not rectified is diagnosed (issue 29, item 4): the rendered street with a
//! right camera pitched so that its rows are 3 or 5 px off the left ones. Before, stereo
//! matching (rows within 1 px) collapsed and the run went on with frames lost and no word
//! of why; now the first frame is refused, naming the row offset. An exact rig and a
//! right camera 0.5 px off (which the self-calibration's rows measure) run as before.

use swarmpose_odometry::{Odometry, OdometryConfig};
use swarmpose_runs::batch::{camera_of, collect};
use swarmpose_runs::synthetic::{RIG, RightCameraError, SyntheticSequence};

fn pitched(rows_px: f64) -> SyntheticSequence {
    SyntheticSequence::new(4, 0.4, 0.0).with_right_camera_error(RightCameraError {
        pitch_rad: (rows_px / RIG.fy).atan(),
        ..RightCameraError::default()
    })
}

#[test]
fn rows_a_few_pixels_off_are_named() {
    for rows_px in [3.0, -5.0] {
        let seq = pitched(rows_px);
        let mut odo = Odometry::new(camera_of(&seq), OdometryConfig::default()).expect("engine");
        let e = collect(&seq, &mut odo, 0.1).expect_err("not rectified");
        let text = e.to_string();
        assert!(
            text.contains("the stereo images are not rectified"),
            "{text}"
        );
        let sign = if rows_px > 0.0 { "+" } else { "-" };
        assert!(text.contains(&format!("rows are {sign}")), "{text}");
        assert!(text.contains("frame 0"), "the first frame: {text}");
    }
}

#[test]
fn a_rectified_rig_and_a_fraction_of_a_pixel_run_as_before() {
    for rows_px in [0.0, 0.5] {
        let run = crate::common::run_sequence(&pitched(rows_px), OdometryConfig::default());
        assert_eq!(run.untracked(), 0, "rows {rows_px} px off");
    }
}
