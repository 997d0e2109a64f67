//! The back end of the engine: from each frame's triangulated features to its pose.
//!
//! State (bounded, whatever the length of the stream): the reference frame (the last
//! frame with enough points) with its pose, the last pose given out, the velocity of the
//! last tracked motion, and the self-calibration's fixed-size evidence.
//!
//! Per frame: match to the reference, the robust estimator's motion, the reprojection
//! refinement ([`crate::refine`]), the self-calibration's update ([`crate::selfcal`]) and,
//! when the correction moved, a second refinement with the new correction. A frame that
//! cannot be tracked is predicted at constant velocity (status
//! [`Status::ConstantVelocity`]) for at most [`OdometryConfig::max_prediction_s`], then
//! held ([`Status::Lost`]); it becomes the new reference if it has enough points (so
//! tracking resumes from it), otherwise the old reference is kept (a frame without
//! texture does not break the chain).

use std::time::Instant;

use nalgebra::{Isometry3, Matrix6, UnitQuaternion};
use swarmpose_core::Estimator;
use swarmpose_vision::features::{Descriptor, GrayView};
use swarmpose_vision::frontend::{DisparityCorrection, StereoFrame, match_frames};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::stereo::RectifiedStereo;
use swarmpose_vision::temporal::TemporalConfig;
use swarmpose_vision::temporal::subpixel::align_patch;

use crate::config::{Calibration, OdometryConfig};
use crate::error::OdometryError;
use crate::estimate::{initial_motion, observations, window_links};
use crate::frontend::ms;
use crate::intake::{StereoCamera, check_timestamp};
use crate::record::{Counts, FrameResult, Reason, StageTimes, Status};
use crate::refine::evidence::MatrixK;
use crate::refine::model::{PixelNoise, StereoModel, StereoObservation};
use crate::refine::split::{SplitCheck, split_check};
use crate::refine::{Refined, refine};
use crate::selfcal::{CorrectionModel, Decision, SelfCalibration};
use crate::window::{Images, Window, WindowMotion};

mod ambiguity;
mod calibrate;
mod predict;

use predict::{Velocity, scale_motion};

/// Mixed into the frame's seed for the search of a second motion among the matches the
/// first left over ([`ambiguity::leftover_motion`]).
const LEFTOVER_SEED: u64 = 0x5EC0_4D00_7105_0000;

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

/// The last pose given out.
#[derive(Debug, Clone, Copy)]
struct Last {
    pose: Isometry3<f64>,
    timestamp_s: f64,
}

/// A measured motion from the reference.
struct Measured {
    motion: Isometry3<f64>,
    covariance: Option<Matrix6<f64>>,
    window: Option<WindowMotion>,
    /// The frame is a keyframe of the window (always without the window).
    keyframe: bool,
    /// The estimator found two distinct motions ([`crate::estimate::Initial`]).
    ambiguous: bool,
    /// The split-feature check ([`OdometryConfig::split_check`]).
    split: Option<SplitCheck>,
    inliers: usize,
    correction: DisparityCorrection,
    focal_px: f64,
    model: CorrectionModel,
    ref_pose: Isometry3<f64>,
    ref_timestamp_s: f64,
    ref_index: usize,
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
    reference: Option<Reference<D>>,
    last: Option<Last>,
    velocity: Option<Velocity>,
    last_tracked_s: Option<f64>,
    /// The last frame's motion was ambiguous ([`FrameResult::ambiguous`]).
    last_ambiguous: bool,
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

    /// The motion of `frame` from the reference, or why there is none.
    fn measure(
        &mut self,
        frame: &StereoFrame<D>,
        left: Option<GrayView<'_>>,
        index: usize,
        timestamp_s: f64,
        times: &mut StageTimes,
        counts: &mut Counts,
    ) -> Result<Measured, Reason> {
        let Some(reference) = self.reference.as_ref() else {
            return Err(Reason::NoReference);
        };
        let (ref_pose, ref_timestamp_s, ref_index) =
            (reference.pose, reference.timestamp_s, reference.index);
        let min = self.config.min_inliers.max(crate::config::MIN_INLIERS);
        let t = Instant::now();
        let m = match_frames(&reference.frame, frame, &self.temporal)
            .map_err(Reason::Matching)?;
        times.match_ms = ms(t);
        counts.matches = m.correspondences.len();
        if counts.matches < min {
            return Err(Reason::TooFewMatches {
                matches: counts.matches,
                min,
            });
        }
        let (correction, model) = self.correction();
        let focal_px = self.focal_px();
        let t = Instant::now();
        let seed = self.config.seed.wrapping_add(index as u64);
        let prediction = self.prediction(ref_timestamp_s, timestamp_s);
        let est = initial_motion(
            &m,
            &correction,
            1.0 + focal_px / self.camera.rig.fx,
            self.camera.rig.baseline_m,
            self.estimator.as_ref(),
            seed,
            min,
        );
        times.estimate_ms = ms(t);
        let initial = est?;
        let start = initial.motion;
        let mut measured = Measured {
            motion: start,
            covariance: None,
            window: None,
            keyframe: true,
            ambiguous: initial.ambiguous,
            split: None,
            inliers: initial.inliers,
            correction,
            focal_px,
            model,
            ref_pose,
            ref_timestamp_s,
            ref_index,
        };
        let needs_evidence = self.config.calibration == Calibration::Auto;
        if !self.config.refine && !needs_evidence {
            return Ok(measured);
        }
        let t = Instant::now();
        let stripes = self.config.selfcal.stripes.max(1) as f64;
        let mut obs = observations(&m, (self.camera.width as f64 / stripes).max(1.0));
        if let (Some(a), Some(b)) = (reference.left.as_ref(), left) {
            // Where A's patches appear in B, to a fraction of a pixel.
            let mut keep = 0;
            for k in 0..obs.current.len() {
                let za = obs.reference[k];
                let zb = obs.current[k];
                if let Some((u, v)) = align_patch(
                    a.view(),
                    (za.u as f32, za.v as f32),
                    b,
                    (zb.u as f32, zb.v as f32),
                    10,
                    2.0,
                ) {
                    obs.reference[keep] = za;
                    obs.current[keep] = StereoObservation {
                        u: f64::from(u),
                        v: f64::from(v),
                        d: zb.d,
                    };
                    obs.folds[keep] = obs.folds[k];
                    obs.source[keep] = obs.source[k];
                    keep += 1;
                }
            }
            obs.reference.truncate(keep);
            obs.current.truncate(keep);
            obs.folds.truncate(keep);
            obs.source.truncate(keep);
        }
        let model_now = self.model(correction, focal_px);
        let mut refined = refine(
            &model_now,
            &self.config.refinement,
            &obs.reference,
            &obs.current,
            Some(&obs.folds),
            &start,
            min,
        )
        .map_err(Reason::Refinement)?;
        if let Some(p) = prediction.as_ref()
            && let Some(second) = ambiguity::second_motion(
                &model_now,
                &self.config.refinement,
                (&obs.reference, &obs.current, &obs.folds),
                &refined,
                p,
                min,
            )
        {
            measured.ambiguous = true;
            if second.preferred {
                refined = second.refined;
            }
        }
        if !measured.ambiguous
            && (prediction.is_none() || self.last_ambiguous)
            && ambiguity::leftover_motion(
                self.estimator.as_ref(),
                &m.correspondences,
                &model_now,
                &self.config.refinement,
                (&obs.reference, &obs.current, &obs.folds, &obs.source),
                &refined,
                min,
                seed ^ LEFTOVER_SEED,
            )
            .is_some()
        {
            measured.ambiguous = true;
        }
        times.refine_ms = ms(t);
        let t = Instant::now();
        let mut best: (Refined, DisparityCorrection, f64, CorrectionModel) =
            (refined, correction, focal_px, model);
        if needs_evidence {
            let mut selfcal = std::mem::take(&mut self.selfcal);
            let dt_s = timestamp_s - ref_timestamp_s;
            best = self.self_calibrate(&mut selfcal, frame, &m, &obs, best, dt_s, min);
            self.selfcal = selfcal;
        }
        times.calibrate_ms += ms(t);
        if self.config.refine {
            // Otherwise the estimator alone: its motion, on the points corrected as
            // decided before this pair.
            let (refined, correction, focal_px, model) = best;
            let calibration_covariance = self.calibration_covariance();
            measured.motion = refined.motion;
            measured.covariance =
                Some(refined.covariance_with_calibration(&calibration_covariance));
            if self.config.split_check {
                measured.split = split_check(
                    (&self.model(correction, focal_px), &calibration_covariance),
                    &self.config.refinement,
                    (&obs.reference, &obs.current),
                    &refined.inliers,
                    &refined.motion,
                    min,
                )
                .ok();
            }
            measured.inliers = refined.inliers.len();
            measured.correction = correction;
            measured.focal_px = focal_px;
            measured.model = model;
            if self.window.enabled() {
                let t = Instant::now();
                let links = window_links(&m, &obs, &refined.inliers);
                let images = match (reference.left.as_ref(), left) {
                    (Some(a), Some(b)) => Some(Images {
                        reference: a.view(),
                        current: b,
                    }),
                    _ => None,
                };
                let pose = ref_pose * measured.motion;
                if let Some((pose, _, window)) = self.window.add(
                    (&self.model(correction, focal_px), &calibration_covariance),
                    (ref_index, &ref_pose),
                    (index, &pose),
                    &links,
                    images,
                ) {
                    // Normalised: the inverse of a unit quaternion is its conjugate, so
                    // rounding in the reference's norm would double with every frame.
                    let mut motion = ref_pose.inverse() * pose;
                    motion.rotation = UnitQuaternion::new_normalize(motion.rotation.into_inner());
                    measured.motion = motion;
                    // The pose given out is the window's, measured from its own (revised)
                    // pose of the reference: the motion from the reference's pose as given
                    // out carries that revision, whose error neither the pair's nor the
                    // window's information describes (RESULTS.md: the pair's covariance
                    // gives a mean NEES of 12.4 for it, the window's 13.4). What is
                    // measured, with its covariance, is the window's motion from its
                    // oldest keyframe.
                    measured.covariance = None;
                    measured.window = Some(window);
                }
                measured.keyframe = self.window.newest_is_keyframe();
                times.window_ms = ms(t);
            }
        }
        Ok(measured)
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
        mut times: StageTimes,
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
        let min = self.config.min_inliers.max(crate::config::MIN_INLIERS);
        let enough_points = frame.len() >= min;
        let n_points = frame.len();

        let too_few = || Reason::TooFewPoints {
            points: n_points,
            min,
        };
        let (correction, correction_model) = self.correction();
        let focal_px = self.focal_px();
        let mut result = FrameResult {
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
            focal_px,
            correction_model,
            keyframe: false,
            ambiguous: false,
            window_poses: Vec::new(),
            split: None,
        };
        let Some(last) = self.last else {
            // The first frame: the origin.
            self.last = Some(Last {
                pose: Isometry3::identity(),
                timestamp_s,
            });
            if enough_points {
                result.keyframe = true;
                self.set_reference(frame, left, Isometry3::identity(), timestamp_s, index);
            } else {
                result.status = Status::Lost(too_few());
            }
            return Ok(result);
        };
        let measured = if enough_points {
            self.measure(&frame, left, index, timestamp_s, &mut times, &mut counts)
        } else {
            Err(too_few())
        };
        result.times = times;
        match measured {
            Ok(m) => {
                let mut pose = m.ref_pose * m.motion;
                pose.rotation = UnitQuaternion::new_normalize(pose.rotation.into_inner());
                self.velocity = Some(Velocity {
                    motion: m.motion,
                    dt_s: timestamp_s - m.ref_timestamp_s,
                });
                self.last_tracked_s = Some(timestamp_s);
                counts.inliers = m.inliers;
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
                // Frame to frame: the tracked frame is the next reference.
                self.set_reference(frame, left, pose, timestamp_s, index);
            }
            Err(why) => {
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
                if enough_points {
                    // Tracking resumes from this frame.
                    self.set_reference(frame, left, result.pose, timestamp_s, index);
                }
            }
        }
        result.counts = counts;
        self.last = Some(Last {
            pose: result.pose,
            timestamp_s,
        });
        Ok(result)
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
