//! What the engine returns for each frame.

use nalgebra::{Isometry3, Matrix6};
use swarmpose_core::PoseError;
use swarmpose_vision::frontend::DisparityCorrection;

use crate::refine::RefineError;
use crate::refine::split::SplitCheck;
use crate::selfcal::CorrectionModel;

/// What happened to the motion into one frame.
#[derive(Debug, Clone, PartialEq)]
pub enum Status {
    /// The first frame: the origin.
    First,
    /// The motion was estimated from the images.
    Tracked,
    /// The motion could not be estimated (the reason): predicted from the last velocity.
    ConstantVelocity(Reason),
    /// No motion could be estimated or predicted (the reason): the pose is held.
    Lost(Reason),
}

/// Why the motion into a frame could not be measured, in the order of the stages that
/// can fail ([`crate::tracker`]). Its text (`Display`) is the reason [`Status::text`]
/// gives in parentheses.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[non_exhaustive]
pub enum Reason {
    /// The frame has fewer 3D points than a motion needs.
    #[error("{points} stereo points, fewer than {min}")]
    TooFewPoints {
        /// Points with a depth in the frame.
        points: usize,
        /// Fewest inliers a motion needs ([`crate::OdometryConfig::min_inliers`]).
        min: usize,
    },
    /// No earlier frame had enough points to measure from.
    #[error("no reference frame with enough points")]
    NoReference,
    /// Matching the frame's features to the reference's failed.
    #[error("matching failed: {0}")]
    Matching(PoseError),
    /// Too few of the frame's features matched the reference's.
    #[error("{matches} matches, fewer than {min}")]
    TooFewMatches {
        /// Matches with the reference frame.
        matches: usize,
        /// Fewest inliers a motion needs.
        min: usize,
    },
    /// The disparity correction could not be applied to the matches' points.
    #[error("disparity correction {correction}: {error}")]
    Correction {
        /// The correction applied.
        correction: DisparityCorrection,
        /// What went wrong.
        error: PoseError,
    },
    /// The focal length change could not be applied to the matches' points.
    #[error("focal length x {scale}: {error}")]
    FocalLength {
        /// Ratio of the focal length applied to the calibration's.
        scale: f64,
        /// What went wrong.
        error: PoseError,
    },
    /// The robust estimator found no motion.
    #[error("estimator: {0}")]
    Estimator(PoseError),
    /// The robust estimator's motion has too few inliers.
    #[error("estimator: {inliers} inliers, fewer than {min}")]
    TooFewInliers {
        /// Inliers of the estimator's motion.
        inliers: usize,
        /// Fewest inliers a motion needs.
        min: usize,
    },
    /// The reprojection refinement failed (too few consistent points, or a motion the
    /// points do not determine).
    #[error("refinement: {0}")]
    Refinement(RefineError),
}

impl Status {
    /// The text of `frames.csv`: `first`, `tracked`, `constant-velocity (REASON)` or
    /// `lost (REASON)`.
    #[must_use]
    pub fn text(&self) -> String {
        match self {
            Status::First => "first".into(),
            Status::Tracked => "tracked".into(),
            Status::ConstantVelocity(why) => format!("constant-velocity ({why})"),
            Status::Lost(why) => format!("lost ({why})"),
        }
    }

    /// True for [`Status::Tracked`].
    #[must_use]
    pub fn is_tracked(&self) -> bool {
        matches!(self, Status::Tracked)
    }
}

/// Wall-clock time of each stage for one frame, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Reading the images (by the caller; 0 when the frame came from memory).
    pub load_ms: f64,
    /// Feature extraction in both images.
    pub features_ms: f64,
    /// Stereo matching and triangulation (or depth lookup).
    pub stereo_ms: f64,
    /// Matching to the reference frame.
    pub match_ms: f64,
    /// The robust estimator.
    pub estimate_ms: f64,
    /// Reprojection refinement.
    pub refine_ms: f64,
    /// Self-calibration (its decision and, when the correction moved, the second
    /// refinement).
    pub calibrate_ms: f64,
    /// The sliding window's refinement ([`crate::window`]; 0 without a window).
    pub window_ms: f64,
}

impl std::ops::AddAssign<&StageTimes> for StageTimes {
    fn add_assign(&mut self, t: &StageTimes) {
        self.load_ms += t.load_ms;
        self.features_ms += t.features_ms;
        self.stereo_ms += t.stereo_ms;
        self.match_ms += t.match_ms;
        self.estimate_ms += t.estimate_ms;
        self.refine_ms += t.refine_ms;
        self.calibrate_ms += t.calibrate_ms;
        self.window_ms += t.window_ms;
    }
}

impl StageTimes {
    /// Sum of the stages.
    #[must_use]
    pub fn total_ms(&self) -> f64 {
        self.load_ms
            + self.features_ms
            + self.stereo_ms
            + self.match_ms
            + self.estimate_ms
            + self.refine_ms
            + self.calibrate_ms
            + self.window_ms
    }
}

/// Feature counts of one frame.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct Counts {
    /// Features detected in the left image.
    pub left_features: usize,
    /// Features detected in the right image (0 for RGB-D).
    pub right_features: usize,
    /// Features with a 3D point (stereo-matched, or with a valid depth).
    pub stereo_points: usize,
    /// Matches with the reference frame.
    pub matches: usize,
    /// Inliers of the accepted motion (0 when none).
    pub inliers: usize,
}

/// One inlier of a tracked frame's motion: the feature in this frame and in the frame
/// its motion was measured from, and its triangulated point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Inlier {
    /// The feature's pixel `(u, v)` in this frame's left image (pixels of the camera's
    /// images, as given to the engine).
    pub pixel: (f32, f32),
    /// Its pixel in the left image of the frame the motion was measured from (the
    /// matched frame: the previous frame, or an earlier one that had more points).
    pub reference_pixel: (f32, f32),
    /// Its point in this frame's left camera frame (x right, y down, z forward), metres,
    /// as triangulated from this frame's images (stereo, or the depth image).
    pub point_m: [f32; 3],
}

/// The engine's answer for one frame.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameResult {
    /// 0-based index of the frame in the stream.
    pub index: usize,
    /// Timestamp, seconds, as given.
    pub timestamp_s: f64,
    /// Pose of the left camera in the left camera frame of the first frame (x right,
    /// y down, z forward, metres): `C_k = C_{k-1} T_{k-1,k}`.
    pub pose: Isometry3<f64>,
    /// The motion from the previous frame, `T_{k-1,k}` (the pose of this camera in the
    /// previous one); identity for the first frame.
    pub motion: Isometry3<f64>,
    /// The frame this frame was measured from: the previous one (or an earlier one when
    /// the frames in between had too few points) for the frame-to-frame refinement; with
    /// the sliding window, the window's oldest keyframe. `None` unless tracked.
    pub reference: Option<usize>,
    /// The motion measured from [`FrameResult::reference`], `T_{ref,k}` (this camera's
    /// pose in the reference camera, metres); the identity unless tracked. Without the
    /// window it equals [`FrameResult::motion`] when the reference is the previous frame.
    /// With the window it is the window's estimate from its oldest keyframe, whose pose
    /// the window may have revised since it was given out, so the pose given out is not
    /// that frame's given-out pose composed with this motion (see [`crate::window`]).
    pub measured_motion: Isometry3<f64>,
    /// Covariance of [`FrameResult::measured_motion`], when it was refined: of
    /// `ξ = (ν, ω)` (metres, radians, in this camera's frame) in `T_true = T ∘ E(ξ)`,
    /// `E(ξ): P ↦ Exp(ω) P + ν`; see [`crate::refine`] and
    /// [`crate::window::WindowMotion::covariance`]. It includes the uncertainty of the
    /// self-calibrated disparity correction (none for a calibration taken as given) and,
    /// with [`crate::OdometryConfig::covariance_floor`] (the default), the systematic
    /// floor learned from the frames before this one ([`crate::refine::floor`]).
    pub covariance: Option<Matrix6<f64>>,
    /// What happened.
    pub status: Status,
    /// Feature counts.
    pub counts: Counts,
    /// Time per stage.
    pub times: StageTimes,
    /// The disparity correction applied to this frame.
    pub correction: DisparityCorrection,
    /// The change of the rig's focal length applied to this frame, pixels of `fx` (`fy`
    /// in proportion; 0 unless the self-calibration chose it).
    pub focal_px: f64,
    /// The model of that correction.
    pub correction_model: CorrectionModel,
    /// True when the frame is a keyframe: with the sliding window, when it became one of
    /// the window's keyframes ([`crate::window`]: it moved beyond the measurement noise
    /// since the last one, or lost most of its tracks); without it, every frame that
    /// later frames are measured from (the first and every tracked frame). False for a
    /// frame that was not tracked.
    pub keyframe: bool,
    /// True when the estimator found two distinct motions with comparable support (at
    /// least its ambiguity ratio, a half by default: a large moving object, or a scene
    /// that repeats). The motion taken is the one nearer the constant-velocity prediction
    /// (the one with more support when there is no recent motion to predict from); the
    /// pose may still be that of the other motion, so treat it with care. Only the robust
    /// PSO (`pso`) looks for a second motion.
    pub ambiguous: bool,
    /// With the sliding window, the window's current estimate of the pose of each frame it
    /// holds (frame index, pose as [`FrameResult::pose`]), oldest first, this frame last:
    /// earlier frames' poses as revised by this frame's refinement. A frame's last
    /// revision (the value it had when it left the window) is the output of a fixed-lag
    /// smoother, at most the window's span late; [`FrameResult::pose`] stays the online
    /// estimate. Empty without the window or for a frame that was not tracked.
    pub window_poses: Vec<(usize, Isometry3<f64>)>,
    /// With [`crate::OdometryConfig::split_check`], the split-feature check of the pair's
    /// covariance ([`crate::refine::split`]): the motion refined on each half of the
    /// inliers, and the normalised difference, judged with the systematic floor learned
    /// from the frames before this one. `None` otherwise, or when a half had too few
    /// inliers.
    pub split: Option<SplitCheck>,
    /// The inliers of the accepted motion from the frame it was matched to: the
    /// refinement's when the motion was refined, the estimator's otherwise (as many as
    /// [`Counts::inliers`]). Empty for a frame that was not tracked.
    pub inliers: Vec<Inlier>,
}

#[cfg(test)]
mod tests {
    use swarmpose_core::PoseError;
    use swarmpose_vision::frontend::DisparityCorrection;

    use super::{Reason, Status};
    use crate::refine::RefineError;

    /// Each reason's text is the one the engine wrote before the reasons were an enum
    /// (frames.csv, Python and the CLI show it): the old format strings, written out.
    #[test]
    fn reasons_read_as_before() {
        let e = PoseError::TooFewPoints { got: 2, needed: 3 };
        let c = DisparityCorrection {
            offset_px: 0.5,
            ..DisparityCorrection::default()
        };
        let cases = [
            (
                Reason::TooFewPoints { points: 7, min: 12 },
                "7 stereo points, fewer than 12".to_owned(),
            ),
            (
                Reason::NoReference,
                "no reference frame with enough points".to_owned(),
            ),
            (Reason::Matching(e.clone()), format!("matching failed: {e}")),
            (
                Reason::TooFewMatches {
                    matches: 5,
                    min: 12,
                },
                "5 matches, fewer than 12".to_owned(),
            ),
            (
                Reason::Correction {
                    correction: c,
                    error: e.clone(),
                },
                format!("disparity correction {c}: {e}"),
            ),
            (
                Reason::FocalLength {
                    scale: 1.0025,
                    error: e.clone(),
                },
                format!("focal length x 1.0025: {e}"),
            ),
            (Reason::Estimator(e.clone()), format!("estimator: {e}")),
            (
                Reason::TooFewInliers {
                    inliers: 9,
                    min: 12,
                },
                "estimator: 9 inliers, fewer than 12".to_owned(),
            ),
            (
                Reason::Refinement(RefineError::TooFewInliers {
                    got: 11,
                    needed: 12,
                }),
                "refinement: 11 points consistent with the motion, fewer than 12".to_owned(),
            ),
        ];
        for (reason, text) in cases {
            assert_eq!(reason.to_string(), text);
            assert_eq!(
                Status::ConstantVelocity(reason.clone()).text(),
                format!("constant-velocity ({text})")
            );
            assert_eq!(Status::Lost(reason).text(), format!("lost ({text})"));
        }
        assert_eq!(
            format!("{e}"),
            "too few correspondences: 2, at least 3 are needed"
        );
    }
}
