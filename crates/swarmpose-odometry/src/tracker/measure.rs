//! The stages of a frame after its front end, in order: match it to the reference, the
//! robust estimator's motion, the reprojection refinement (on patch-aligned
//! measurements, with the check for a second motion), the self-calibration's update,
//! and the sliding window. Each stage is one step below; [`Tracker::measure`] runs them
//! top to bottom, and the first that fails gives the frame's [`Reason`].

use std::time::Instant;

use nalgebra::{Isometry3, Matrix6, UnitQuaternion};
use swarmpose_vision::features::{Descriptor, GrayView};
use swarmpose_vision::frontend::{
    DisparityCorrection, FrameMatches, MotionGuide, StereoFrame, match_frames_guided, match_share,
};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::temporal::subpixel::align_patch_with;
use swarmpose_vision::temporal::template::PatchTemplate;

use super::calibrate::Best;
use super::{Reference, Tracker, ambiguity};
use crate::config::Calibration;
use crate::estimate::{
    Initial, Observations, initial_motion, inlier_features, observations, window_links,
};
use crate::frontend::ms;
use crate::record::{Counts, Inlier, Reason, StageTimes};
use crate::refine::model::StereoObservation;
use crate::refine::split::{SplitCheck, split_check};
use crate::refine::{Refined, refine};
use crate::selfcal::CorrectionModel;
use crate::window::{Images, WindowMotion};

/// Mixed into the frame's seed for the search of a second motion among the matches the
/// first left over ([`ambiguity::leftover_motion`]).
const LEFTOVER_SEED: u64 = 0x5EC0_4D00_7105_0000;

/// The frame being tracked.
pub(super) struct Current<'a, D> {
    /// Its triangulated features.
    pub(super) frame: &'a StereoFrame<D>,
    /// Its left image, when the frame came with one (for sub-pixel matching).
    pub(super) left: Option<GrayView<'a>>,
    /// Its index in the stream.
    pub(super) index: usize,
    /// Its timestamp, seconds.
    pub(super) timestamp_s: f64,
    /// Its matches found ahead of time, if any ([`super::Prematched`]).
    pub(super) prematched: Option<super::Prematched>,
}

/// A frame's matches with the reference and their stereo measurements (patch-aligned
/// in the current frame when both frames came with images).
struct Pair {
    matches: FrameMatches,
    obs: Observations,
}

/// A measured motion from the reference.
pub(super) struct Measured {
    pub(super) motion: Isometry3<f64>,
    pub(super) covariance: Option<Matrix6<f64>>,
    pub(super) window: Option<WindowMotion>,
    /// The frame is a keyframe of the window (always without the window).
    pub(super) keyframe: bool,
    /// The estimator found two distinct motions ([`crate::estimate::Initial`]).
    pub(super) ambiguous: bool,
    /// The split-feature check ([`crate::OdometryConfig::split_check`]).
    pub(super) split: Option<SplitCheck>,
    /// The pair's split-feature check under the model, for the systematic floor to learn
    /// from once the frame's covariances have been given theirs.
    pub(super) floor_sample: Option<SplitCheck>,
    pub(super) inliers: usize,
    /// The inliers' features ([`crate::FrameResult::inliers`]).
    pub(super) features: Vec<Inlier>,
    pub(super) correction: DisparityCorrection,
    pub(super) focal_px: f64,
    pub(super) model: CorrectionModel,
    pub(super) ref_pose: Isometry3<f64>,
    pub(super) ref_timestamp_s: f64,
    pub(super) ref_index: usize,
}

impl<D: Descriptor> Tracker<D> {
    /// The motion of the frame `now` from the reference, or why there is none.
    pub(super) fn measure(
        &mut self,
        now: Current<'_, D>,
        times: &mut StageTimes,
        counts: &mut Counts,
    ) -> Result<Measured, Reason> {
        // Out of the state while the steps change the rest of it; put back whatever
        // happens, for the next reference to reuse its image buffer.
        let reference = self.reference.take().ok_or(Reason::NoReference)?;
        let measured = self.measure_from(&reference, now, times, counts);
        self.reference = Some(reference);
        measured
    }

    /// [`Tracker::measure`] from `reference`: the frame's stages, top to bottom.
    fn measure_from(
        &mut self,
        reference: &Reference<D>,
        mut now: Current<'_, D>,
        times: &mut StageTimes,
        counts: &mut Counts,
    ) -> Result<Measured, Reason> {
        let prematched = now.prematched.take();
        let matches = self.match_step(reference, &now, prematched, times, counts)?;
        let (correction, model) = self.correction();
        let focal_px = self.focal_px();
        let seed = self.config.seed.wrapping_add(now.index as u64);
        let initial = self.estimate_step(&matches, &correction, focal_px, seed, times)?;
        let mut measured = Measured {
            motion: initial.motion,
            covariance: None,
            window: None,
            keyframe: true,
            ambiguous: initial.ambiguous,
            split: None,
            floor_sample: None,
            inliers: initial.inliers,
            features: inlier_features(&matches, initial.inlier_matches.iter().copied()),
            correction,
            focal_px,
            model,
            ref_pose: reference.pose,
            ref_timestamp_s: reference.timestamp_s,
            ref_index: reference.index,
        };
        let needs_evidence = self.config.calibration == Calibration::Auto;
        if !self.config.refine && !needs_evidence {
            return Ok(measured);
        }
        let t = Instant::now();
        let obs = self.aligned_observations(&matches, reference.left.as_ref(), now.left);
        let pair = Pair { matches, obs };
        let prediction = self.prediction(reference.timestamp_s, now.timestamp_s);
        let refined = self.refine_step(&pair, &initial, prediction, (correction, focal_px), seed);
        let (refined, ambiguous) = refined?;
        measured.ambiguous = ambiguous;
        times.refine_ms = ms(t);
        let dt_s = now.timestamp_s - reference.timestamp_s;
        let best = (refined, correction, focal_px, model);
        let best = self.calibrate_step(now.frame, &pair, best, dt_s, times);
        if self.config.refine {
            // Otherwise the estimator alone: its motion, on the points corrected as
            // decided before this pair.
            self.take_refined(&mut measured, &best, &pair.obs);
            let inliers = best
                .0
                .inliers
                .iter()
                .filter_map(|&k| pair.obs.source.get(k));
            measured.features = inlier_features(&pair.matches, inliers.copied());
            if self.window.enabled() {
                let t = Instant::now();
                self.window_step(&mut measured, reference, now, &pair, &best);
                times.window_ms = ms(t);
            }
        }
        // Learned after it was used: a frame's floor comes from the frames before it.
        if let Some(sample) = &measured.floor_sample {
            self.floor.learn(sample);
        }
        Ok(measured)
    }

    /// Fewest inliers of a motion ([`crate::OdometryConfig::min_inliers`], at least
    /// [`crate::config::MIN_INLIERS`]).
    pub(super) fn min_inliers(&self) -> usize {
        self.config.min_inliers.max(crate::config::MIN_INLIERS)
    }

    /// Match: the frame's features matched to the reference's, near where the
    /// constant-velocity prediction puts them when there is one and the configuration asks
    /// for it ([`swarmpose_vision::temporal::TemporalConfig::guided_radius_px`]), held to
    /// the share of the features the last pair matched. Matches found ahead of time
    /// (`prematched`) are taken when they are with this reference and the search is not
    /// guided: they are the same matches.
    fn match_step(
        &mut self,
        reference: &Reference<D>,
        now: &Current<'_, D>,
        prematched: Option<super::Prematched>,
        times: &mut StageTimes,
        counts: &mut Counts,
    ) -> Result<FrameMatches, Reason> {
        let min = self.min_inliers();
        let usable = prematched.filter(|p| {
            self.temporal.guided_radius_px.is_none()
                && p.reference_timestamp_s.to_bits() == reference.timestamp_s.to_bits()
        });
        let m = if let Some(p) = usable {
            times.match_ms = p.match_ms;
            p.matches
        } else {
            let t = Instant::now();
            let prediction = self.prediction(reference.timestamp_s, now.timestamp_s);
            let guide =
                prediction
                    .as_ref()
                    .zip(self.last_match_share)
                    .map(|(motion, last_share)| MotionGuide {
                        motion,
                        rig: &self.camera.rig,
                        last_share,
                    });
            let (m, _) = match_frames_guided(&reference.frame, now.frame, &self.temporal, guide)
                .map_err(Reason::Matching)?;
            times.match_ms = ms(t);
            m
        };
        self.last_match_share = Some(match_share(
            &reference.frame,
            now.frame,
            m.correspondences.len(),
        ));
        counts.matches = m.correspondences.len();
        if counts.matches < min {
            return Err(Reason::TooFewMatches {
                matches: counts.matches,
                min,
            });
        }
        Ok(m)
    }

    /// Estimate: the robust estimator's motion on the matches' points, under the
    /// `correction` and focal length change `focal_px` applied now.
    fn estimate_step(
        &self,
        m: &FrameMatches,
        correction: &DisparityCorrection,
        focal_px: f64,
        seed: u64,
        times: &mut StageTimes,
    ) -> Result<Initial, Reason> {
        let t = Instant::now();
        let initial = initial_motion(
            m,
            correction,
            1.0 + focal_px / self.camera.rig.fx,
            self.camera.rig.baseline_m,
            self.estimator.as_ref(),
            seed,
            self.min_inliers(),
        );
        times.estimate_ms = ms(t);
        initial
    }

    /// The stereo measurements of the matches `m`, with the current frame's moved to
    /// where the reference's patches appear in it, to a fraction of a pixel, when both
    /// frames came with images ([`crate::refine::RefineConfig::align_iterations`]); a
    /// match whose patch is not found is left out.
    fn aligned_observations(
        &self,
        m: &FrameMatches,
        reference: Option<&GrayImage>,
        current: Option<GrayView<'_>>,
    ) -> Observations {
        let stripes = self.config.selfcal.stripes.max(1) as f64;
        let mut obs = observations(m, (self.camera.width as f64 / stripes).max(1.0));
        let (Some(a), Some(b)) = (reference, current) else {
            return obs;
        };
        let config = &self.config.refinement;
        let mut keep = 0;
        // One template for the frame's alignments (each sampling overwrites it).
        let mut template = PatchTemplate::empty();
        for k in 0..obs.current.len() {
            let za = obs.reference[k];
            let zb = obs.current[k];
            if let Some((u, v)) = align_patch_with(
                &mut template,
                a.view(),
                (za.u as f32, za.v as f32),
                b,
                (zb.u as f32, zb.v as f32),
                config.align_iterations,
                config.align_max_move_px,
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
        obs
    }

    /// Refine: the estimator's motion `initial` refined on the pair's measurements under
    /// the correction and focal length change applied now, then the checks for a second
    /// motion ([`ambiguity`]): near the constant-velocity `prediction`, or, without one
    /// (or after an ambiguous frame), among the matches the first motion left over. The
    /// motion taken, and whether the frame is ambiguous.
    fn refine_step(
        &self,
        pair: &Pair,
        initial: &Initial,
        prediction: Option<Isometry3<f64>>,
        (correction, focal_px): (DisparityCorrection, f64),
        seed: u64,
    ) -> Result<(Refined, bool), Reason> {
        let min = self.min_inliers();
        let (config, obs) = (&self.config.refinement, &pair.obs);
        let model = self.model(correction, focal_px);
        let measurements = (&obs.reference[..], &obs.current[..]);
        let mut refined = refine(
            &model,
            config,
            measurements.0,
            measurements.1,
            Some(&obs.folds),
            &initial.motion,
            min,
        )
        .map_err(Reason::Refinement)?;
        let mut ambiguous = initial.ambiguous;
        if let Some(p) = prediction.as_ref()
            && let Some(second) = ambiguity::second_motion(
                &model,
                config,
                (measurements.0, measurements.1, &obs.folds),
                &refined,
                p,
                min,
            )
        {
            ambiguous = true;
            if second.preferred {
                refined = second.refined;
            }
        }
        if !ambiguous
            && (prediction.is_none() || self.last_ambiguous)
            && ambiguity::leftover_motion(
                self.estimator.as_ref(),
                &pair.matches.correspondences,
                &model,
                config,
                (measurements.0, measurements.1, &obs.folds, &obs.source),
                &refined,
                min,
                seed ^ LEFTOVER_SEED,
            )
            .is_some()
        {
            ambiguous = true;
        }
        Ok((refined, ambiguous))
    }

    /// Calibrate: the pair's evidence added to the self-calibration (with
    /// [`Calibration::Auto`]), and the pair refined again under the correction it leads
    /// to; `best` as it is otherwise. The frame was taken `dt_s` seconds after the
    /// reference.
    fn calibrate_step(
        &mut self,
        frame: &StereoFrame<D>,
        pair: &Pair,
        best: Best,
        dt_s: f64,
        times: &mut StageTimes,
    ) -> Best {
        let t = Instant::now();
        let mut best = best;
        if self.config.calibration == Calibration::Auto {
            let mut selfcal = std::mem::take(&mut self.selfcal);
            let min = self.min_inliers();
            best = self.self_calibrate(
                &mut selfcal,
                frame,
                &pair.matches,
                &pair.obs,
                best,
                dt_s,
                min,
            );
            self.selfcal = selfcal;
        }
        times.calibrate_ms += ms(t);
        best
    }

    /// The refined motion `best` (with the correction it was refined under) as the
    /// frame's measurement: its covariance with the calibration's uncertainty and the
    /// systematic floor added, and the split-feature check when it is asked for or the
    /// floor learns from it.
    fn take_refined(&self, measured: &mut Measured, best: &Best, obs: &Observations) {
        let (refined, correction, focal_px, model) = best;
        let calibration_covariance = self.calibration_covariance();
        measured.motion = refined.motion;
        let covariance = refined.covariance_with_calibration(&calibration_covariance);
        measured.covariance = Some(self.floor.widen(&covariance));
        if self.config.split_check || self.floor.enabled() {
            let raw = split_check(
                (&self.model(*correction, *focal_px), &calibration_covariance),
                &self.config.refinement,
                (&obs.reference, &obs.current),
                &refined.inliers,
                &refined.motion,
                self.min_inliers(),
            )
            .ok();
            let asked = self.config.split_check;
            measured.split = raw.filter(|_| asked).map(|s| self.floor.judge(&s));
            measured.floor_sample = raw.filter(|_| self.floor.enabled());
        }
        measured.inliers = refined.inliers.len();
        measured.correction = *correction;
        measured.focal_px = *focal_px;
        measured.model = *model;
    }

    /// Window: the frame added to the sliding window with the refined pair's inliers;
    /// the window's motion, when it has one, replaces the pair's.
    fn window_step(
        &mut self,
        measured: &mut Measured,
        reference: &Reference<D>,
        now: Current<'_, D>,
        pair: &Pair,
        (refined, correction, focal_px, _): &Best,
    ) {
        let links = window_links(&pair.matches, &pair.obs, &refined.inliers);
        let images = match (reference.left.as_ref(), now.left) {
            (Some(a), Some(b)) => Some(Images {
                reference: a.view(),
                current: b,
            }),
            _ => None,
        };
        let ref_pose = reference.pose;
        let pose = ref_pose * measured.motion;
        if let Some((pose, _, window)) = self.window.add(
            (
                &self.model(*correction, *focal_px),
                &self.calibration_covariance(),
            ),
            (reference.index, &ref_pose),
            (now.index, &pose),
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
            let covariance = window.covariance.map(|c| self.floor.widen(&c));
            measured.window = Some(WindowMotion {
                covariance,
                ..window
            });
        }
        measured.keyframe = self.window.newest_is_keyframe();
    }
}
