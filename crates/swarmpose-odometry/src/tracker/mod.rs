//! The back end of the engine: from each frame's triangulated features to its pose.
//!
//! State (bounded, whatever the length of the stream): the reference frame (the last
//! frame with enough points) with its pose, the last pose given out, the velocity of the
//! last tracked motion, and the self-calibration's fixed-size evidence.
//!
//! Per frame: match to the reference, the robust estimator's motion, the reprojection
//! refinement ([`crate::refine`]), the self-calibration's update ([`crate::selfcal`]) and,
//! when the correction moved, a second refinement with the new correction, and the
//! sliding window ([`crate::window`]): one named step each, run top to bottom by
//! `measure` (`tracker/measure.rs`); the first that fails gives the frame's
//! [`crate::Reason`]. A frame that cannot be tracked is predicted at constant velocity
//! (status [`Status::ConstantVelocity`]) for at most
//! [`OdometryConfig::max_prediction_s`], then held ([`Status::Lost`]); it becomes the new
//! reference if it has enough points (so tracking resumes from it), otherwise the old
//! reference is kept (a frame without texture does not break the chain).

use nalgebra::{Isometry3, UnitQuaternion};
use swarmpose_core::Estimator;
use swarmpose_vision::features::{Descriptor, GrayView};
use swarmpose_vision::frontend::{DisparityCorrection, FrameMatches, StereoFrame};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::stereo::RectifiedStereo;
use swarmpose_vision::temporal::TemporalConfig;

use crate::config::{Calibration, OdometryConfig};
use crate::error::OdometryError;
use crate::intake::{StereoCamera, check_timestamp};
use crate::record::{Counts, FrameResult, Reason, StageTimes, Status};
use crate::refine::evidence::MatrixK;
use crate::refine::floor::SystematicFloor;
use crate::refine::model::{PixelNoise, StereoModel};
use crate::selfcal::{CorrectionModel, Decision, SelfCalibration};
use crate::window::Window;

mod ambiguity;
mod calibrate;
mod measure;
mod predict;

use measure::{Current, Measured};
use predict::{Velocity, scale_motion};

/// The frame that the next one is matched to.
#[derive(Debug, Clone)]
struct Reference<D> {
    frame: StereoFrame<D>,
    /// Its left image, when the frame came with one (for sub-pixel matching).
    left: Option<GrayImage>,
    pose: Isometry3<f64>,
    timestamp_s: f64,
    index: usize,
}

/// A frame's matches with the frame it is expected to be tracked from, found ahead of
/// time (by the front-end thread of [`crate::Odometry::run_two_threads`], while the back
/// end works on the frame before). [`Tracker::track_prematched`] uses them only when that
/// frame is the reference and the matching is not guided by a prediction (which needs the
/// back end's state): they are then what the back end would have found, computed by the
/// same function on the same frames.
#[derive(Debug, Clone)]
pub(crate) struct Prematched {
    /// The timestamp of the frame matched to, seconds: it names the frame, since the
    /// timestamps increase strictly.
    pub(crate) reference_timestamp_s: f64,
    /// The matches, as [`swarmpose_vision::frontend::match_frames`] gives them with the
    /// reference as `dst`.
    pub(crate) matches: FrameMatches,
    /// The time they took, milliseconds.
    pub(crate) match_ms: f64,
}

/// The last pose given out.
#[derive(Debug, Clone, Copy)]
struct Last {
    pose: Isometry3<f64>,
    timestamp_s: f64,
}

/// `rig` with its focal length changed by `focal_px` pixels of `fx`, `fy` in proportion.
fn focal_changed(rig: &RectifiedStereo, focal_px: f64) -> RectifiedStereo {
    let mut r = *rig;
    r.fy *= 1.0 + focal_px / r.fx;
    r.fx += focal_px;
    r
}

/// The back end: poses from triangulated frames.
pub struct Tracker<D: Descriptor> {
    camera: StereoCamera,
    noise: PixelNoise,
    temporal: TemporalConfig,
    config: OdometryConfig,
    estimator: Box<dyn Estimator>,
    selfcal: SelfCalibration,
    window: Window,
    /// The systematic floor of the covariance, learned from past frames.
    floor: SystematicFloor,
    reference: Option<Reference<D>>,
    last: Option<Last>,
    velocity: Option<Velocity>,
    last_tracked_s: Option<f64>,
    /// The last frame's motion was ambiguous ([`FrameResult::ambiguous`]).
    last_ambiguous: bool,
    /// The share of the features the last pair matched
    /// ([`swarmpose_vision::frontend::match_share`]), which a guided search is held to.
    last_match_share: Option<f32>,
    next_index: usize,
}

impl<D: Descriptor> Tracker<D> {
    /// A tracker for `camera` whose measurements have `noise`, matching frames with
    /// `temporal`. The engine refuses a `config` it cannot honour
    /// ([`OdometryConfig::check`]); a tracker made directly takes `min_inliers` as at
    /// least [`crate::config::MIN_INLIERS`].
    #[must_use]
    pub fn new(
        camera: StereoCamera,
        noise: PixelNoise,
        temporal: TemporalConfig,
        config: OdometryConfig,
        estimator: Box<dyn Estimator>,
    ) -> Self {
        let selfcal = SelfCalibration::new(config.selfcal);
        let window = Window::new(config.window);
        Self {
            window,
            floor: SystematicFloor::new(config.covariance_floor),
            camera,
            noise,
            temporal,
            config,
            estimator,
            selfcal,
            reference: None,
            last: None,
            velocity: None,
            last_tracked_s: None,
            last_ambiguous: false,
            last_match_share: None,
            next_index: 0,
        }
    }

    /// The estimator's name.
    #[must_use]
    pub fn estimator_name(&self) -> &'static str {
        self.estimator.name()
    }

    /// The self-calibration's current decision and evidence.
    #[must_use]
    pub fn calibration(&self) -> &Decision {
        self.selfcal.decision()
    }

    /// Timestamp of the last frame taken, seconds.
    #[must_use]
    pub fn last_timestamp_s(&self) -> Option<f64> {
        self.last.map(|l| l.timestamp_s)
    }

    /// Heap bytes held by the state (the reference frame's features and the window's
    /// keyframes), for checks that memory does not grow with the stream.
    #[must_use]
    pub fn state_bytes(&self) -> usize {
        use nalgebra::{Matrix3, Point3};
        use swarmpose_vision::features::Keypoint;
        self.window.heap_bytes()
            + self.reference.as_ref().map_or(0, |r| {
                let f = &r.frame;
                (f.left_keypoints.capacity() + f.right_keypoints.capacity()) * size_of::<Keypoint>()
                    + (f.left_descriptors.capacity() + f.right_descriptors.capacity())
                        * size_of::<D>()
                    + f.points.capacity() * size_of::<Point3<f64>>()
                    + f.disparities_px.capacity() * size_of::<f32>()
                    + f.sigmas_m.capacity() * size_of::<f64>()
                    + f.covariances.capacity() * size_of::<Matrix3<f64>>()
            })
    }

    /// The disparity correction applied to the next frame and where it comes from: the
    /// self-calibration's decision, [`CorrectionModel::GIVEN`] for a fixed one, or none.
    #[must_use]
    pub fn correction(&self) -> (DisparityCorrection, CorrectionModel) {
        match self.config.calibration {
            Calibration::Auto => {
                let d = self.selfcal.decision();
                (d.correction, d.model)
            }
            Calibration::Off => (DisparityCorrection::default(), CorrectionModel::NONE),
            Calibration::Fixed(c) => (c, CorrectionModel::GIVEN),
        }
    }

    /// The change of the rig's focal length applied to the next frame, pixels of `fx`
    /// (`fy` in proportion): the self-calibration's, or 0 for a fixed or no correction.
    #[must_use]
    pub fn focal_px(&self) -> f64 {
        match self.config.calibration {
            Calibration::Auto => self.selfcal.decision().focal_px,
            Calibration::Off | Calibration::Fixed(_) => 0.0,
        }
    }

    /// Covariance of the calibration terms applied (pixels²): the self-calibration's,
    /// zero for a calibration taken as given.
    fn calibration_covariance(&self) -> MatrixK {
        match self.config.calibration {
            Calibration::Auto => self.selfcal.decision().covariance,
            Calibration::Off | Calibration::Fixed(_) => MatrixK::zeros(),
        }
    }

    fn model(&self, correction: DisparityCorrection, focal_px: f64) -> StereoModel {
        StereoModel {
            rig: focal_changed(&self.camera.rig, focal_px),
            noise: self.noise,
            correction,
        }
    }

    /// Takes the triangulated features of the next frame, taken at `timestamp_s`, and
    /// returns its pose. `times` carries the caller's stage times (loading, front end).
    ///
    /// # Errors
    /// [`OdometryError::Frame`] for a timestamp that is not finite or does not increase;
    /// the state is then unchanged.
    pub fn track(
        &mut self,
        frame: StereoFrame<D>,
        left: Option<GrayView<'_>>,
        timestamp_s: f64,
        times: StageTimes,
    ) -> Result<FrameResult, OdometryError> {
        self.track_prematched(frame, left, timestamp_s, times, None)
    }

    /// What is needed to match a frame ahead of time ([`Prematched`]): the temporal
    /// matching's configuration and the fewest stereo points of a frame that becomes the
    /// reference; `None` when the matching is guided by the back end's prediction.
    pub(crate) fn prematching(&self) -> Option<(TemporalConfig, usize)> {
        self.temporal
            .guided_radius_px
            .is_none()
            .then_some((self.temporal, self.min_inliers()))
    }

    /// [`Tracker::track`] with the frame's matches found ahead of time, used when they
    /// are with the reference ([`Prematched`]); the result is the same.
    pub(crate) fn track_prematched(
        &mut self,
        frame: StereoFrame<D>,
        left: Option<GrayView<'_>>,
        timestamp_s: f64,
        mut times: StageTimes,
        prematched: Option<Prematched>,
    ) -> Result<FrameResult, OdometryError> {
        check_timestamp(timestamp_s, self.last.map(|l| l.timestamp_s))?;
        let index = self.next_index;
        self.next_index += 1;
        let mut counts = Counts {
            left_features: frame.n_left_features,
            right_features: frame.n_right_features,
            stereo_points: frame.len(),
            ..Counts::default()
        };
        let mut result = self.first_result(index, timestamp_s, counts, times);
        let min = self.min_inliers();
        let too_few = (frame.len() < min).then_some(Reason::TooFewPoints {
            points: frame.len(),
            min,
        });
        let Some(last) = self.last else {
            self.take_first(&mut result, frame, left, too_few);
            return Ok(result);
        };
        let enough_points = too_few.is_none();
        let measured = match too_few {
            Some(why) => Err(why),
            None => {
                let now = Current {
                    frame: &frame,
                    left,
                    index,
                    timestamp_s,
                    prematched,
                };
                self.measure(now, &mut times, &mut counts)
            }
        };
        result.times = times;
        let pose = match measured {
            Ok(m) => self.take_tracked(&mut result, &mut counts, m, &last),
            Err(why) => self.take_untracked(&mut result, why, &last),
        };
        if enough_points {
            // Tracking goes on, or resumes, from this frame.
            self.set_reference(frame, left, pose, timestamp_s, index);
        }
        result.counts = counts;
        self.last = Some(Last {
            pose: result.pose,
            timestamp_s,
        });
        Ok(result)
    }

    /// The result of frame `index` before it is measured: the first frame's (the
    /// origin), with the correction applied now.
    fn first_result(
        &self,
        index: usize,
        timestamp_s: f64,
        counts: Counts,
        times: StageTimes,
    ) -> FrameResult {
        let (correction, correction_model) = self.correction();
        FrameResult {
            index,
            timestamp_s,
            pose: Isometry3::identity(),
            motion: Isometry3::identity(),
            reference: None,
            measured_motion: Isometry3::identity(),
            covariance: None,
            status: Status::First,
            counts,
            times,
            correction,
            focal_px: self.focal_px(),
            correction_model,
            keyframe: false,
            ambiguous: false,
            window_poses: Vec::new(),
            split: None,
            inliers: Vec::new(),
        }
    }

    /// The first frame: the origin, and the reference unless it has too few points
    /// (`too_few`, then it is lost).
    fn take_first(
        &mut self,
        result: &mut FrameResult,
        frame: StereoFrame<D>,
        left: Option<GrayView<'_>>,
        too_few: Option<Reason>,
    ) {
        self.last = Some(Last {
            pose: Isometry3::identity(),
            timestamp_s: result.timestamp_s,
        });
        match too_few {
            None => {
                result.keyframe = true;
                let (timestamp_s, index) = (result.timestamp_s, result.index);
                self.set_reference(frame, left, Isometry3::identity(), timestamp_s, index);
            }
            Some(why) => result.status = Status::Lost(why),
        }
    }

    /// A tracked frame: its pose from the measured motion `m`, which becomes the
    /// velocity; returns the pose (frame to frame: the frame is the next reference).
    fn take_tracked(
        &mut self,
        result: &mut FrameResult,
        counts: &mut Counts,
        m: Measured,
        last: &Last,
    ) -> Isometry3<f64> {
        let timestamp_s = result.timestamp_s;
        let mut pose = m.ref_pose * m.motion;
        pose.rotation = UnitQuaternion::new_normalize(pose.rotation.into_inner());
        self.velocity = Some(Velocity {
            motion: m.motion,
            dt_s: timestamp_s - m.ref_timestamp_s,
        });
        self.last_tracked_s = Some(timestamp_s);
        counts.inliers = m.inliers;
        result.inliers = m.features;
        result.pose = pose;
        result.motion = last.pose.inverse() * pose;
        match m.window {
            Some(w) => {
                result.reference = Some(w.keyframe);
                result.measured_motion = w.motion;
                result.covariance = w.covariance;
            }
            None => {
                result.reference = Some(m.ref_index);
                result.measured_motion = m.motion;
                result.covariance = m.covariance;
            }
        }
        result.status = Status::Tracked;
        result.keyframe = m.keyframe;
        result.ambiguous = m.ambiguous;
        result.split = m.split;
        self.last_ambiguous = m.ambiguous;
        if self.window.enabled() {
            result.window_poses = self.window.poses().collect();
        }
        result.correction = m.correction;
        result.focal_px = m.focal_px;
        result.correction_model = m.model;
        pose
    }

    /// A frame that could not be measured (`why`): the window is emptied, and the status
    /// decided: predicted at constant velocity while the last tracked motion is recent
    /// ([`OdometryConfig::max_prediction_s`]), otherwise lost with the pose held. Returns
    /// the pose (the frame is the next reference if it has enough points).
    fn take_untracked(
        &mut self,
        result: &mut FrameResult,
        why: Reason,
        last: &Last,
    ) -> Isometry3<f64> {
        let timestamp_s = result.timestamp_s;
        self.window.clear();
        self.last_ambiguous = false;
        let horizon = self.config.max_prediction_s;
        let velocity = self.velocity.filter(|_| {
            self.last_tracked_s
                .is_some_and(|t| timestamp_s - t <= horizon)
        });
        let (motion, status) = match velocity {
            Some(v) if v.dt_s > 0.0 => (
                scale_motion(&v.motion, (timestamp_s - last.timestamp_s) / v.dt_s),
                Status::ConstantVelocity(why),
            ),
            _ => (Isometry3::identity(), Status::Lost(why)),
        };
        result.pose = last.pose * motion;
        result.motion = motion;
        result.status = status;
        result.pose
    }

    fn set_reference(
        &mut self,
        frame: StereoFrame<D>,
        left: Option<GrayView<'_>>,
        pose: Isometry3<f64>,
        timestamp_s: f64,
        index: usize,
    ) {
        // The previous reference's image buffer is reused.
        let mut image = self.reference.take().and_then(|r| r.left);
        let left = left.map(|v| {
            let mut img = image.take().unwrap_or_else(|| GrayImage::new(0, 0));
            img.width = v.width;
            img.height = v.height;
            img.data.clear();
            img.data.extend_from_slice(v.data);
            img
        });
        self.reference = Some(Reference {
            frame,
            left,
            pose,
            timestamp_s,
            index,
        });
    }
}
