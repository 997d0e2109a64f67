//! Feature tracks and a sliding window of keyframes refined jointly on the reprojection
//! error (a local bundle adjustment), on top of the frame-to-frame engine.
//!
//! **Tracks.** Every tracked pair's inlier matches link a feature of the reference frame to
//! one of the current frame; a feature that continues a track gets its identity, any other
//! starts a new one. A track is one 3D point, anchored by inverse depth in the first
//! keyframe of the window that sees it ([`crate::refine::model`]), and it is re-estimated
//! with every new observation. Its measurement in each frame is where the image patch of
//! the frame where it began appears (a [`PatchTemplate`](swarmpose_vision::temporal::template::PatchTemplate) aligned under an affine warp, to
//! a fraction of a pixel), so that every frame measures the same physical point without
//! the errors of the detected keypoints (whole pixels, moving with the corner's apparent
//! size) and without the bias a translation-only alignment takes from the patch's growing
//! scale and shear; a track whose patch is not found again ends.
//!
//! **Keyframes.** The engine measures each frame against the previous one, and the window
//! holds [`WindowConfig::keyframes`] frames: the newest and the keyframes before it. The newest
//! frame becomes a keyframe when its measurements have moved beyond their noise since the
//! last keyframe, or when that keyframe no longer holds most of its tracks
//! ([`KEYFRAME_MIN_MOVE`]); otherwise it is refined with the window, its pose given out, and it
//! leaves the window when the next frame arrives. A camera that stands still (or creeps)
//! is then measured against one keyframe instead of adding the noise of every pair to its
//! path, and how often keyframes come does not follow the frame rate alone. A frame that is
//! not tracked (constant velocity, lost) empties the window; it starts again from the next
//! tracked pair.
//!
//! **Refinement** ([`solve`]). The poses of the window's keyframes except the oldest (held
//! fixed: it fixes the gauge) and the points of every track seen at least twice are
//! refined together on the whitened residuals of all their stereo measurements `(u, v, d)`,
//! with a Huber loss, by Levenberg-Marquardt with the points eliminated by their 3x3 Schur
//! complements, at most [`WindowConfig::max_iterations`] iterations: the time per frame is
//! bounded by the window's size. The pose given out for the current frame is the window's.
//! Poses already given out are not revised (the engine is online), but the window keeps
//! their refined values for the next frames.
//!
//! **Marginalisation** ([`marginal`], off by default: [`WindowConfig::marginalise`]). When
//! the oldest keyframe leaves, its information is discarded by default; optionally its
//! pose and the tracks that go with it are marginalised into a Gaussian prior on the
//! remaining keyframes' relative poses, added to every later refinement.
//!
//! Memory is bounded: at most `keyframes` frames, each with its own observations, and the
//! track identities and patches of the newest frame's features.

mod calibration;
mod ids;
mod link;
pub mod marginal;
mod prior;
mod residual;
pub mod solve;
mod templates;
mod tracks;

use std::collections::VecDeque;

use ids::{IdMap, IdSet};

use nalgebra::{Isometry3, Matrix6, UnitQuaternion};

use swarmpose_vision::features::GrayView;

use crate::refine::evidence::MatrixK;
use crate::refine::model::{StereoModel, StereoObservation};

pub use marginal::Marginalisation;

/// Settings of the sliding window.
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct WindowConfig {
    /// Keyframes in the window, K (default 10; 0: no window, frame to frame only). 2 is
    /// the frame-to-frame refinement again; from 3 on, tracks span several frames. The
    /// default was chosen by the measurements of every sequence this project has (RESULTS.md,
    /// "Feature tracks and a sliding window"), not for one of them.
    pub keyframes: usize,
    /// Most Levenberg-Marquardt iterations per frame (default 1: the window is refined
    /// again with every frame, starting from its last solution; 1, 3 and 5 give the same
    /// results to the digits RESULTS.md prints, at a third of the time of 3).
    pub max_iterations: usize,
    /// Huber threshold on a measurement's whitened residual norm (default 2.5, as in the
    /// frame-to-frame refinement).
    pub huber_k: f64,
    /// What happens to the oldest keyframe's information when it leaves the window
    /// (default [`Marginalisation::Off`]: discarded; docs/window.md has the measurements).
    pub marginalise: Marginalisation,
    /// Each measurement keeps the disparity correction in use for the frame where it was
    /// made, and a new correction enters the window through new measurements only (module
    /// `window::calibration`; issue 30), so that a change of the self-calibration does not
    /// rescale the window's keyframes and jump the online pose (default false: the window
    /// solves every measurement under the newest correction). It is not the default: at the
    /// frames where the correction's model changes, the online steps follow the smoothed
    /// ones within 0.6 % instead of 1.35 % (kitti_vo_seq2) and 6.0 % (Karlsruhe), but the
    /// drift and Karlsruhe's ATE grow (docs/self-calibration.md has every sequence).
    pub correction_per_frame: bool,
}

impl Default for WindowConfig {
    fn default() -> Self {
        Self {
            keyframes: 10,
            max_iterations: 1,
            huber_k: 2.5,
            marginalise: Marginalisation::Off,
            correction_per_frame: false,
        }
    }
}

/// An inlier match of a tracked pair: the feature's index in the reference frame and in
/// the current frame, and its measurement in each.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Link {
    /// Index of the feature in the reference frame.
    pub reference_feature: usize,
    /// Index of the feature in the current frame.
    pub current_feature: usize,
    /// Its measurement in the reference frame: the detected keypoint.
    pub reference: StereoObservation,
    /// Where the reference keypoint's patch appears in the current frame (the pair's
    /// measurement; the detected keypoint when there are no images).
    pub current: StereoObservation,
    /// The detected keypoint in the current frame.
    pub current_keypoint: StereoObservation,
}

/// The left images of the reference and the current frame, for the tracks' templates.
#[derive(Debug, Clone, Copy)]
pub struct Images<'a> {
    /// The reference frame's left image.
    pub reference: GrayView<'a>,
    /// The current frame's left image.
    pub current: GrayView<'a>,
}

/// One keyframe of the window.
#[derive(Debug, Clone)]
pub(crate) struct Keyframe {
    /// Frame index in the stream.
    pub index: usize,
    /// Pose of the world in the camera, `T_kw` (metres): `P_k = T_kw P_w`.
    pub pose_cw: Isometry3<f64>,
    /// Its measurements, each of one track.
    pub observations: Vec<(u32, StereoObservation)>,
    /// True for a keyframe; false for the newest frame when it is not one (it leaves
    /// the window when the next frame arrives).
    pub keyframe: bool,
}

/// What one refinement of the window did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowReport {
    /// Keyframes in the window.
    pub keyframes: usize,
    /// Tracks seen at least twice (the points refined).
    pub tracks: usize,
    /// Their measurements.
    pub observations: usize,
    /// Levenberg-Marquardt iterations.
    pub iterations: usize,
    /// True when the newest frame became a keyframe ([`KEYFRAME_MIN_MOVE`]).
    pub keyframe: bool,
    /// Covariance of the newest keyframe's pose relative to the oldest (fixed) one, from
    /// the window's information: see [`WindowMotion::covariance`].
    pub covariance: Option<Matrix6<f64>>,
}

/// The window's measurement of its newest keyframe: the motion from its oldest keyframe
/// (held fixed), which is what the window's information describes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WindowMotion {
    /// Frame index of the window's oldest keyframe.
    pub keyframe: usize,
    /// The pose of the newest camera in the oldest keyframe's camera, `T_{j,k}` (metres),
    /// as the window estimates it. The pose given out is the window's pose of that
    /// keyframe composed with this motion.
    pub motion: Isometry3<f64>,
    /// Covariance of `ξ = (ν, ω)` (metres, radians, in camera `k`) in
    /// `T_true = T ∘ E(ξ)`, as for the pair's motion ([`crate::refine`]): the newest
    /// pose's block of the inverse of the window's reduced information (points
    /// eliminated, the oldest pose fixed), scaled by the residuals' variance factor,
    /// plus the calibration's uncertainty carried through the window's sensitivity to
    /// the calibration terms. `None` when singular.
    pub covariance: Option<Matrix6<f64>>,
}

/// The window: keyframes, and the track of each feature of the newest.
#[derive(Debug, Clone, Default)]
pub struct Window {
    config: WindowConfig,
    frames: VecDeque<Keyframe>,
    /// Track of each feature (by index) of the newest keyframe.
    newest_tracks: IdMap<usize, u32>,
    /// The patch of each live track in the frame where it began (with images).
    templates: templates::Templates,
    next_track: u32,
    /// The prior left by the keyframes marginalised so far ([`WindowConfig::marginalise`]).
    prior: Option<prior::Prior>,
    /// Buffers reused from frame to frame: the refinement's, the next
    /// [`Window::newest_tracks`], the tracks of the newest frame, the measurement buffers
    /// of keyframes that left, and the keyframe rule's.
    workspace: solve::Workspace,
    next_tracks: IdMap<usize, u32>,
    used: IdSet<u32>,
    spare: Vec<Vec<(u32, StereoObservation)>>,
    rule: KeyframeRule,
}

impl Window {
    /// An empty window.
    #[must_use]
    pub fn new(config: WindowConfig) -> Self {
        Self {
            config,
            ..Self::default()
        }
    }

    /// True when the window is on (more than two keyframes).
    #[must_use]
    pub fn enabled(&self) -> bool {
        self.config.keyframes > 2
    }

    /// Empties the window (after a frame that was not tracked).
    pub fn clear(&mut self) {
        while let Some(f) = self.frames.pop_back() {
            self.recycle(f);
        }
        self.newest_tracks.clear();
        self.templates.clear();
        self.prior = None;
    }

    /// Keeps the measurement buffer of `frame`, which left, for a next keyframe (a few).
    fn recycle(&mut self, frame: Keyframe) {
        if self.spare.len() < 2 {
            let mut buffer = frame.observations;
            buffer.clear();
            self.spare.push(buffer);
        }
    }

    /// A new track identity.
    fn new_track(&mut self) -> u32 {
        let t = self.next_track;
        self.next_track = self.next_track.wrapping_add(1);
        t
    }

    /// Keyframes held now.
    #[must_use]
    pub fn len(&self) -> usize {
        self.frames.len()
    }

    /// True when the newest frame held is a keyframe ([`KEYFRAME_MIN_MOVE`]); false when it is
    /// not, or the window is empty.
    #[must_use]
    pub fn newest_is_keyframe(&self) -> bool {
        self.frames.back().is_some_and(|f| f.keyframe)
    }

    /// The frames held (frame index, pose of the camera in the world), oldest first.
    pub fn poses(&self) -> impl Iterator<Item = (usize, Isometry3<f64>)> + '_ {
        self.frames.iter().map(|f| {
            let mut p = f.pose_cw.inverse();
            p.rotation = UnitQuaternion::new_normalize(p.rotation.into_inner());
            (f.index, p)
        })
    }

    /// True when no keyframe is held.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.frames.is_empty()
    }

    /// Heap bytes held: keyframes, their measurements, the newest frame's tracks, and the
    /// buffers kept for the next frame.
    #[must_use]
    pub fn heap_bytes(&self) -> usize {
        let observations = |v: &Vec<(u32, StereoObservation)>| {
            v.capacity() * size_of::<(u32, StereoObservation)>()
        };
        self.frames.capacity() * size_of::<Keyframe>()
            + self
                .frames
                .iter()
                .map(|f| observations(&f.observations))
                .sum::<usize>()
            + self.spare.iter().map(observations).sum::<usize>()
            + (self.newest_tracks.capacity() + self.next_tracks.capacity())
                * (size_of::<usize>() + size_of::<u32>())
            + self.used.capacity() * size_of::<u32>()
            + self.templates.heap_bytes()
            + self.prior.as_ref().map_or(0, prior::Prior::heap_bytes)
            + self.workspace.heap_bytes()
            + self.rule.heap_bytes()
    }

    /// Measurements held now, over all keyframes (bounded by the window's size).
    #[must_use]
    pub fn observations(&self) -> usize {
        self.frames.iter().map(|f| f.observations.len()).sum()
    }

    /// Adds the tracked frame `index`, measured from the frame `reference_index` (posed at
    /// `reference_pose`, the camera in the world) with the inlier `links`, at the pose
    /// `pose` (the camera in the world, from the pair alone); refines the window with
    /// `model` (whose calibration terms have the covariance `calibration_covariance`,
    /// pixels², for the covariance of the result; with
    /// [`WindowConfig::correction_per_frame`] its disparity correction is taken by this
    /// frame's measurements only, as `calibration.rs` says) and returns the current frame's refined pose, what was done and the
    /// window's measurement of the frame, or `None` when the window is too short to add
    /// anything to the pair (or the refinement failed; the pair's pose stands then).
    ///
    /// With `images`, a track's measurement in each frame is where the patch of the frame
    /// where it began appears ([`PatchTemplate::align_affine`](swarmpose_vision::temporal::template::PatchTemplate::align_affine)): the same physical point
    /// in every frame. A track whose patch is not found again ends there, and its feature begins a
    /// new track at its detected keypoint. Without images, the detected keypoints.
    pub fn add(
        &mut self,
        (model, calibration_covariance): (&StereoModel, &MatrixK),
        (reference_index, reference_pose): (usize, &Isometry3<f64>),
        (index, pose): (usize, &Isometry3<f64>),
        links: &[Link],
        images: Option<Images<'_>>,
    ) -> Option<(Isometry3<f64>, WindowReport, WindowMotion)> {
        if !self.enabled() {
            return None;
        }
        if self.frames.back().map(|f| f.index) != Some(reference_index) {
            // A gap: start again from the reference frame.
            self.clear();
            self.frames.push_back(Keyframe {
                index: reference_index,
                pose_cw: reference_pose.inverse(),
                observations: Vec::new(),
                keyframe: true,
            });
        }
        // The pair's motion, from the window's own (refined) pose of the reference.
        let motion = reference_pose.inverse() * pose;
        let start = self
            .frames
            .back()
            .map_or(*pose, |r| r.pose_cw.inverse() * motion);
        let mut observations = self.spare.pop().unwrap_or_default();
        observations.reserve(links.len());
        let model = &if self.config.correction_per_frame {
            self.link_tracks(Some(model), links, images, &mut observations);
            // The measurements are corrected, each by its frame's correction: the window
            // solves with none of its own ([`calibration`]).
            calibration::solver_model(model)
        } else {
            // Every measurement as it was measured, solved under the newest correction.
            self.link_tracks(None, links, images, &mut observations);
            *model
        };
        let current = Keyframe {
            index,
            pose_cw: start.inverse(),
            observations,
            keyframe: false,
        };
        let dropped = self.push_newest(model, current);
        // Two frames that are a pair add nothing to the pair's refinement; two that are
        // not (the newest measured from a frame that left) do.
        if self.frames.len() < 3 && !dropped {
            return None;
        }
        self.refine_newest(model, calibration_covariance)
    }

    /// Adds the newest frame `current`: the frame before it leaves unless it is a
    /// keyframe (its tracks go on in this one; returns true then), `current` becomes a
    /// keyframe or not ([`KeyframeRule`]), and the oldest keyframes leave to make room,
    /// their information marginalised into the prior on the others or discarded.
    fn push_newest(&mut self, model: &StereoModel, mut current: Keyframe) -> bool {
        let dropped = self.frames.back().is_some_and(|f| !f.keyframe);
        if dropped && let Some(f) = self.frames.pop_back() {
            self.recycle(f);
        }
        current.keyframe = self
            .frames
            .back()
            .is_none_or(|last| self.rule.is_keyframe(last, &current, &model.noise));
        while self.frames.len() >= self.config.keyframes {
            if self.config.marginalise != Marginalisation::Off {
                self.prior = marginal::marginalise(
                    model,
                    &self.config,
                    self.frames.make_contiguous(),
                    self.prior.take(),
                    &self.used,
                    self.config.marginalise,
                );
            }
            if let Some(f) = self.frames.pop_front() {
                self.recycle(f);
            }
        }
        self.frames.push_back(current);
        dropped
    }

    /// Refines the window ([`solve::refine_window`]) and returns the newest frame's pose
    /// (the camera in the world), what was done, and the window's motion of the newest
    /// frame from its oldest keyframe.
    fn refine_newest(
        &mut self,
        model: &StereoModel,
        calibration_covariance: &MatrixK,
    ) -> Option<(Isometry3<f64>, WindowReport, WindowMotion)> {
        let report = solve::refine_window(
            model,
            calibration_covariance,
            &self.config,
            self.frames.make_contiguous(),
            self.prior.as_ref(),
            &mut self.workspace,
        )?;
        let newest = self.frames.back()?;
        let oldest = self.frames.front()?;
        let mut motion = oldest.pose_cw * newest.pose_cw.inverse();
        motion.rotation = UnitQuaternion::new_normalize(motion.rotation.into_inner());
        let measured = WindowMotion {
            keyframe: oldest.index,
            motion,
            covariance: report.covariance,
        };
        Some((newest.pose_cw.inverse(), report, measured))
    }
}

/// Median change of a frame's measurements since the last keyframe, in standard
/// deviations of a difference of two measurements (`√2 σ` for `u`, `v` and `d`), above
/// which the frame is a keyframe: noise alone gives a median of about 1.5 (the χ
/// distribution with 3 degrees of freedom), a move of 3 is about 2 px in the image at the
/// default 0.5 px. Set a priori, not measured on any sequence.
pub const KEYFRAME_MIN_MOVE: f64 = 3.0;

/// The keyframe rule ([`KeyframeRule::is_keyframe`]) with its buffers, reused from frame
/// to frame.
#[derive(Debug, Clone, Default)]
pub(crate) struct KeyframeRule {
    seen: IdMap<u32, StereoObservation>,
    moves: Vec<f64>,
}

impl KeyframeRule {
    /// True when `current` is to be a keyframe after `last` (the window's newest
    /// keyframe): fewer than half of `current`'s measurements are of tracks `last` sees
    /// (the window would lose them), or their median change since `last`, whitened by the
    /// noise of a difference of two measurements, is above [`KEYFRAME_MIN_MOVE`] (the frame
    /// adds a view the window does not have).
    #[must_use]
    pub(crate) fn is_keyframe(
        &mut self,
        last: &Keyframe,
        current: &Keyframe,
        noise: &crate::refine::model::PixelNoise,
    ) -> bool {
        let Self { seen, moves } = self;
        seen.clear();
        seen.extend(last.observations.iter().copied());
        let (sp, sd) = (
            std::f64::consts::SQRT_2 * noise.position_px,
            std::f64::consts::SQRT_2 * noise.disparity_px,
        );
        moves.clear();
        moves.extend(current.observations.iter().filter_map(|(t, z)| {
            seen.get(t).map(|y| {
                (((z.u - y.u) / sp).powi(2)
                    + ((z.v - y.v) / sp).powi(2)
                    + ((z.d - y.d) / sd).powi(2))
                .sqrt()
            })
        }));
        if moves.is_empty() || 2 * moves.len() < current.observations.len() {
            return true;
        }
        let mid = moves.len() / 2;
        let (_, median, _) = moves.select_nth_unstable_by(mid, f64::total_cmp);
        *median > KEYFRAME_MIN_MOVE
    }

    /// Heap bytes held.
    fn heap_bytes(&self) -> usize {
        self.seen.capacity() * (size_of::<u32>() + size_of::<StereoObservation>())
            + self.moves.capacity() * size_of::<f64>()
    }
}

#[cfg(test)]
mod tests;
