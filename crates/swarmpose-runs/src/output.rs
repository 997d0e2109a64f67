//! The text of a run's outputs, one line per frame as soon as the frame is done (the
//! caller appends each line to its file and flushes it, so that a run stopped at any
//! point leaves whole lines for every finished frame):
//!
//! * `trajectory.kitti.txt` and `trajectory.tum.txt`: the poses
//!   ([`swarmpose_eval::trajectory`]'s formats);
//! * `frames.csv` ([`FRAMES_HEADER`]): status, counts, stage times, the motion, the
//!   position and the disparity correction of every frame;
//! * `motion_covariance.csv` ([`COVARIANCE_HEADER`]): every tracked frame's measured
//!   motion from its reference frame and the motion's 6x6 covariance.
//!
//! And at the end, the summary ([`Summary`]).

use nalgebra::Isometry3;
use swarmpose_core::geometry::quaternion_wxyz;
use swarmpose_eval::trajectory::{kitti_text, stamp_text, tum_text};

use swarmpose_odometry::{Decision, FrameResult, Status};

/// The header of `frames.csv`.
pub const FRAMES_HEADER: &str = "frame,timestamp_s,status,reference,left_features,\
right_features,stereo_points,matches,inliers,load_ms,features_ms,stereo_ms,match_ms,\
estimate_ms,refine_ms,calibrate_ms,window_ms,total_ms,tx,ty,tz,qw,qx,qy,qz,x,y,z,correction_model,\
correction_offset_px,correction_quadratic_px,correction_linear_px,focal_correction_px,keyframe,\
ambiguous";

/// One row of `frames.csv`, its fields: the frame, its timestamp, status
/// (`first`, `tracked`, `constant-velocity (why)`, `lost (why)`), the frame its motion
/// was measured from, counts, time per stage (ms), the motion from the previous frame
/// (`T_{k-1,k}`: translation metres and quaternion), the position of the camera, and the
/// disparity correction (its constant, `x²` and `x` terms) and the change of the focal
/// length (pixels of `fx`) applied, and
/// whether the frame is a keyframe (1 or 0, [`FrameResult::keyframe`]) and whether its
/// motion was ambiguous (1 or 0, [`FrameResult::ambiguous`]). Written as a CSV record
/// ([`csv_record`]).
#[must_use]
pub fn frames_row(r: &FrameResult) -> Vec<String> {
    let t = r.motion.translation.vector;
    let p = r.pose.translation.vector;
    let (tm, c, k) = (&r.times, &r.counts, &r.correction);
    let mut row = vec![
        r.index.to_string(),
        stamp_text(r.timestamp_s),
        r.status.text(),
        r.reference.map_or_else(String::new, |i| i.to_string()),
    ];
    let counts = [
        c.left_features,
        c.right_features,
        c.stereo_points,
        c.matches,
        c.inliers,
    ];
    row.extend(counts.map(|n| n.to_string()));
    let stages = [
        tm.load_ms,
        tm.features_ms,
        tm.stereo_ms,
        tm.match_ms,
        tm.estimate_ms,
    ];
    row.extend(fixed(stages, 3));
    let stages = [tm.refine_ms, tm.calibrate_ms, tm.window_ms, tm.total_ms()];
    row.extend(fixed(stages, 3));
    row.extend(fixed([t.x, t.y, t.z], 6));
    row.extend(fixed(quaternion_wxyz(&r.motion.rotation), 9));
    row.extend(fixed([p.x, p.y, p.z], 6));
    row.push(r.correction_model.name().to_owned());
    let correction = [k.offset_px, k.quadratic_px, k.linear_x_px, r.focal_px];
    row.extend(fixed(correction, 4));
    row.extend([r.keyframe, r.ambiguous].map(|b| u8::from(b).to_string()));
    row
}

/// `values` written with `decimals` decimals.
fn fixed<const N: usize>(values: [f64; N], decimals: usize) -> [String; N] {
    values.map(|v| format!("{v:.decimals$}"))
}

/// One CSV record of `fields`, without its line end: a field is quoted only when it holds
/// a comma, a quote (written twice) or a line break, as the `csv` crate (and every CSV
/// reader) does it.
///
/// # Errors
/// None in practice: the record is written to memory, and the fields are text.
pub fn csv_record<I>(fields: I) -> Result<String, csv::Error>
where
    I: IntoIterator,
    I::Item: AsRef<[u8]>,
{
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(fields)?;
    let mut bytes = w
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    bytes.pop(); // the record's `\n`
    String::from_utf8(bytes).map_err(|e| csv::Error::from(std::io::Error::other(e)))
}

/// The header of `motion_covariance.csv`.
pub const COVARIANCE_HEADER: &str = "# Each tracked frame's measured motion T from its \
reference frame (pose of camera k in the reference camera: translation metres, quaternion; \
frame to frame the previous frame, with the sliding window the window's oldest keyframe) \
and its covariance: of xi = (nu_x, nu_y, nu_z, omega_x, omega_y, omega_z), metres and \
radians in the frame of camera k, with T_true = T o E(xi), E(xi): P -> Exp(omega) P + nu; \
the self-calibrated disparity correction's uncertainty included. Upper triangle, row by row (c_ij for \
i <= j, 0-based).\n\
frame,reference,tx,ty,tz,qw,qx,qy,qz,c00,c01,c02,c03,c04,c05,c11,c12,c13,c14,c15,c22,c23,\
c24,c25,c33,c34,c35,c44,c45,c55";

/// One row of `motion_covariance.csv`, its fields, for a frame with a covariance.
#[must_use]
pub fn covariance_row(r: &FrameResult) -> Option<Vec<String>> {
    let c = r.covariance?;
    let t = r.measured_motion.translation.vector;
    let mut row = vec![r.index.to_string(), r.reference?.to_string()];
    row.extend(fixed([t.x, t.y, t.z], 6));
    row.extend(fixed(quaternion_wxyz(&r.measured_motion.rotation), 9));
    for i in 0..6 {
        for j in i..6 {
            row.push(format!("{:e}", c[(i, j)]));
        }
    }
    Some(row)
}

/// The KITTI line of a pose (no line end).
#[must_use]
pub fn kitti_line(pose: &Isometry3<f64>) -> String {
    kitti_text(std::slice::from_ref(pose)).trim_end().to_owned()
}

/// The TUM line of a pose at `timestamp_s` (no line end).
#[must_use]
pub fn tum_line(timestamp_s: f64, pose: &Isometry3<f64>) -> String {
    tum_text(&[timestamp_s], std::slice::from_ref(pose))
        .trim_end()
        .to_owned()
}

/// Smallest share of the motions (frames after the first) that must be tracked for a
/// run to be usable ([`Summary::not_usable`]).
pub const MIN_TRACKED_SHARE: f64 = 0.5;

/// Counts of a run's frames by status, updated frame by frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Summary {
    /// Frames taken.
    pub frames: usize,
    /// Frames whose motion was tracked.
    pub tracked: usize,
    /// Frames predicted at constant velocity.
    pub constant_velocity: usize,
    /// Frames lost (a first frame without enough points included).
    pub lost: usize,
    /// Keyframes ([`FrameResult::keyframe`]).
    pub keyframes: usize,
    /// Frames whose motion was ambiguous ([`FrameResult::ambiguous`]).
    pub ambiguous: usize,
}

impl Summary {
    /// Counts one more frame.
    pub fn add(&mut self, r: &FrameResult) {
        self.frames += 1;
        self.keyframes += usize::from(r.keyframe);
        self.ambiguous += usize::from(r.ambiguous);
        match r.status {
            Status::First => {}
            Status::Tracked => self.tracked += 1,
            Status::ConstantVelocity(_) => self.constant_velocity += 1,
            Status::Lost(_) => self.lost += 1,
        }
    }

    /// The motions: one per frame after the first.
    #[must_use]
    pub fn motions(&self) -> usize {
        self.frames.saturating_sub(1)
    }

    /// Share of the motions that were tracked, in `[0, 1]` (0 for fewer than 2 frames).
    #[must_use]
    pub fn tracked_share(&self) -> f64 {
        if self.frames < 2 {
            0.0
        } else {
            self.tracked as f64 / self.motions() as f64
        }
    }

    /// Why the run is not usable, when fewer than [`MIN_TRACKED_SHARE`] of its motions
    /// were tracked (the command line's exit status 3, Python's `NotUsableError`).
    #[must_use]
    pub fn not_usable(&self) -> Option<String> {
        let share = self.tracked_share();
        (share < MIN_TRACKED_SHARE).then(|| {
            format!(
                "not usable: {} motions of {} were tracked ({:.0} %, fewer than {:.0} %; {} at \
                 constant velocity, {} lost)",
                self.tracked,
                self.motions(),
                100.0 * share,
                100.0 * MIN_TRACKED_SHARE,
                self.constant_velocity,
                self.lost
            )
        })
    }

    /// `N frames: T of M motions tracked, C at constant velocity, L lost, K keyframes`,
    /// and `, A ambiguous` when there were any.
    #[must_use]
    pub fn text(&self) -> String {
        let mut s = format!(
            "{} frames: {} of {} motions tracked, {} at constant velocity, {} lost, {} keyframes",
            self.frames,
            self.tracked,
            self.motions(),
            self.constant_velocity,
            self.lost,
            self.keyframes
        );
        if self.ambiguous > 0 {
            s.push_str(&format!(", {} ambiguous", self.ambiguous));
        }
        s
    }
}

/// The self-calibration's decision as JSON: the causes chosen, the correction's
/// coefficients, and the evidence of the rows (their `x y` bend, which is a yaw only when
/// taken as one; roll and pitch) and of rigidity (held-out scores, the margin the next
/// term missed, counts).
#[must_use]
pub fn calibration_json(d: &Decision) -> serde_json::Value {
    let terms: serde_json::Map<String, serde_json::Value> =
        swarmpose_vision::frontend::DisparityCorrection::TERM_NAMES
            .iter()
            .zip(d.correction.coefficients())
            .map(|(n, c)| (format!("{n}_px"), serde_json::json!(c)))
            .collect();
    let r = &d.rows;
    serde_json::json!({
        "model": d.model.name(),
        "coefficients": terms,
        "focal_length_change_px": d.focal_px,
        "rows": {
            "measurements": r.measurements,
            // The rows' x*y bend is what a yaw of the right camera shows, and what a
            // rectification left with lens distortion shows too: it is named by its
            // shape, and a yaw only when the decision took it as one (the summary line
            // says the same).
            "xy_bend_px": r.rotation_px[0],
            "xy_bend_taken_as_yaw": r.yaw,
            "roll": r.roll,
            "pitch": r.pitch,
            "f_roll_px": r.rotation_px[1],
            "f_pitch_px": r.rotation_px[2],
            "vertical_scale_px": r.vertical_scale_px,
            "vertical_scale": r.vertical_scale,
            "held_out_score_chi2": r.score,
            "applied_fraction": r.weight,
        },
        "rigidity": {
            "pairs": d.pairs,
            "one_plane_pairs": d.one_plane_pairs,
            "unobservable": d.rigidity_unobservable(),
            "held_out_score_chi2": d.rigidity_score,
            "next_term_held_out_score_chi2": d.rigidity_next_score,
            "applied_fraction": d.rigidity_weight,
        },
        "frames": d.frames,
    })
}

/// The fixed-lag smoothed trajectory of a run: each frame's last estimate by the sliding
/// window (the value its pose had when it left the window, or has now for the frames the
/// window still holds), from [`FrameResult::window_poses`]; a frame's online pose without
/// the window. Grows by one pose a frame: it is for runs that keep their trajectory.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Smoothed {
    poses: Vec<Isometry3<f64>>,
}

impl Smoothed {
    /// Takes the next frame's result (frames in order, from frame 0).
    pub fn add(&mut self, r: &FrameResult) {
        self.poses.push(r.pose);
        for (i, p) in &r.window_poses {
            if let Some(s) = self.poses.get_mut(*i) {
                *s = *p;
            }
        }
    }

    /// The poses so far, one per frame.
    #[must_use]
    pub fn poses(&self) -> &[Isometry3<f64>] {
        &self.poses
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rows' `x y` bend is reported by its shape; "yaw" appears only as whether the
    /// decision took it as one (issue 30: a user reading "yaw" would re-calibrate a rig
    /// that may be fine).
    #[test]
    fn calibration_json_names_the_rows_bend_by_its_shape() {
        let mut d = Decision::default();
        d.rows.rotation_px = [-6.76, 0.25, 0.0];
        let json = calibration_json(&d);
        let rows = &json["rows"];
        assert_eq!(rows["xy_bend_px"], serde_json::json!(-6.76));
        assert_eq!(rows["xy_bend_taken_as_yaw"], serde_json::json!(false));
        assert_eq!(rows["f_roll_px"], serde_json::json!(0.25));
        let keys: Vec<&String> = rows.as_object().expect("an object").keys().collect();
        let yaw: Vec<&&String> = keys.iter().filter(|k| k.contains("yaw")).collect();
        assert_eq!(yaw, [&"xy_bend_taken_as_yaw"], "{keys:?}");
        d.rows.yaw = true;
        assert_eq!(
            calibration_json(&d)["rows"]["xy_bend_taken_as_yaw"],
            serde_json::json!(true)
        );
    }
}
