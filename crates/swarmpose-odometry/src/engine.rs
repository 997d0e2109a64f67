//! The streaming odometry engine: frames in, poses out.
//!
//! ```no_run
//! use swarmpose_odometry::{Odometry, OdometryConfig, StereoCamera, StereoInput};
//! # fn frames() -> Vec<(swarmpose_vision::image::GrayImage, swarmpose_vision::image::GrayImage, f64)> { vec![] }
//! let camera = StereoCamera {
//!     rig: swarmpose_vision::stereo::RectifiedStereo {
//!         fx: 718.856, fy: 718.856, cx: 607.19, cy: 185.22, baseline_m: 0.537,
//!     },
//!     width: 1241,
//!     height: 376,
//! };
//! let mut odometry = Odometry::new(camera, OdometryConfig::default())?;
//! for (left, right, t) in frames() {
//!     let r = odometry.track(StereoInput { left: left.view(), right: right.view(), timestamp_s: t })?;
//!     println!("{} {:?} {}", r.index, r.pose.translation.vector, r.status.text());
//! }
//! # Ok::<(), swarmpose_odometry::OdometryError>(())
//! ```

use std::ops::ControlFlow;

use swarmpose_core::Estimator;
use swarmpose_vision::features::{
    BinaryDescriptor, Descriptor, FeatureExtractor, FloatDescriptor64,
};
use swarmpose_vision::frontend::{Detector, Frontend, StereoFrame, match_frames};
use swarmpose_vision::image::GrayImage;
use swarmpose_vision::orb::OrbExtractor;
use swarmpose_vision::surf::Surf;
use swarmpose_vision::temporal::TemporalConfig;

use crate::config::{Calibration, OdometryConfig};
use crate::error::{OdometryError, RunFailure};
use crate::frontend::{RgbdNoise, rgbd_frame, stereo_frame};
use crate::intake::{RgbdInput, StereoCamera, StereoInput, check_rgbd, check_stereo};
use crate::record::{FrameResult, StageTimes};
use crate::refine::model::PixelNoise;
use crate::selfcal::Decision;
use crate::tracker::{Prematched, Tracker};
use crate::working::{Resampler, WorkingScale};

/// The front end and back end for one detector.
enum Inner {
    Orb(Box<Frontend<OrbExtractor>>, Tracker<BinaryDescriptor>),
    Surf(Box<Frontend<Surf>>, Tracker<FloatDescriptor64>),
}

/// Calls `$body` with the front end and tracker, whatever the detector.
macro_rules! with_inner {
    ($inner:expr, $f:ident, $t:ident => $body:expr) => {
        match $inner {
            Inner::Orb($f, $t) => $body,
            Inner::Surf($f, $t) => $body,
        }
    };
}

/// The sensor the engine takes frames from.
#[derive(Debug, Clone, Copy, PartialEq)]
enum Sensor {
    Stereo,
    Rgbd(RgbdNoise),
}

/// A streaming visual odometry: created for one camera, it takes one frame at a time
/// and returns that frame's pose at once ([`FrameResult`]). Its memory does not grow
/// with the number of frames. Frames from any source: a directory or a bag (the
/// `swarmpose-runs` crate), a camera driver, a Python array.
pub struct Odometry {
    /// The camera the frames come from.
    camera: StereoCamera,
    sensor: Sensor,
    inner: Inner,
    /// Halvings or doublings of the stereo images before any work ([`crate::working`]).
    scale: WorkingScale,
    /// The camera of the working images.
    working_camera: StereoCamera,
    /// Buffers of the resampled left and right images.
    resampled: [Resampler; 2],
}

/// Builds an [`Odometry`] with a chosen estimator or for an RGB-D camera.
#[must_use]
pub struct OdometryBuilder {
    camera: StereoCamera,
    config: OdometryConfig,
    estimator: Option<Box<dyn Estimator>>,
    rgbd: Option<RgbdNoise>,
}

impl OdometryBuilder {
    /// The configuration (default [`OdometryConfig::default`]).
    pub fn config(mut self, config: OdometryConfig) -> Self {
        self.config = config;
        self
    }

    /// The robust estimator of the motion, in place of the configuration's
    /// ([`OdometryConfig::estimator`]): for an estimator of the embedder's own.
    pub fn estimator(mut self, estimator: Box<dyn Estimator>) -> Self {
        self.estimator = Some(estimator);
        self
    }

    /// An RGB-D camera with this depth noise model: frames go to
    /// [`Odometry::track_rgbd`]; the camera's baseline is not used, and there is no
    /// disparity correction.
    pub fn rgbd(mut self, noise: RgbdNoise) -> Self {
        self.rgbd = Some(noise);
        self
    }

    /// The engine.
    ///
    /// # Errors
    /// [`OdometryError::Camera`] for a camera that is not valid, or an RGB-D camera with
    /// a detector other than ORB; [`OdometryError::Config`] for a setting out of its
    /// range ([`OdometryConfig::check`]).
    pub fn build(self) -> Result<Odometry, OdometryError> {
        let mut camera = self.camera;
        let config = self.config;
        config.check()?;
        if let Some(noise) = &self.rgbd {
            noise.validate()?;
            camera.rig.baseline_m = noise.virtual_baseline_m;
        }
        camera.validate()?;
        // Stereo images are brought to the working size; RGB-D frames never.
        let scale = match self.rgbd {
            Some(_) => WorkingScale::default(),
            None => WorkingScale::for_camera(
                &camera,
                (config.min_working_pixels, config.max_working_pixels),
            )?,
        };
        let working_camera = scale.camera(&camera);
        let mut config = scale.config(&config);
        let estimator = self.estimator.unwrap_or_else(|| config.estimator.build());
        let sensor = match self.rgbd {
            Some(noise) => {
                if config.detector != Detector::Orb {
                    return Err(OdometryError::Camera {
                        message: format!(
                            "detector {} is not available for RGB-D input (use orb)",
                            config.detector
                        ),
                    });
                }
                config.calibration = Calibration::Off;
                Sensor::Rgbd(noise)
            }
            None => Sensor::Stereo,
        };
        let work = working_camera;
        let inner = match config.detector {
            Detector::Orb => {
                let f = Frontend::orb_with(work.rig, &config.orb);
                let noise = config
                    .pixel_noise
                    .unwrap_or_else(|| noise_of(&f.stereo, sensor, &work));
                let t = Tracker::new(work, noise, f.temporal, config, estimator);
                Inner::Orb(Box::new(f), t)
            }
            Detector::Surf => {
                let f = Frontend::surf_with(work.rig, &config.surf);
                let noise = config
                    .pixel_noise
                    .unwrap_or_else(|| noise_of(&f.stereo, sensor, &work));
                let t = Tracker::new(work, noise, f.temporal, config, estimator);
                Inner::Surf(Box::new(f), t)
            }
        };
        Ok(Odometry {
            camera,
            sensor,
            inner,
            scale,
            working_camera,
            resampled: [Resampler::default(), Resampler::default()],
        })
    }
}

fn noise_of(
    stereo: &swarmpose_vision::stereo::StereoConfig,
    sensor: Sensor,
    camera: &StereoCamera,
) -> PixelNoise {
    match sensor {
        Sensor::Stereo => PixelNoise {
            position_px: stereo.position_sigma_px,
            disparity_px: stereo.disparity_sigma_px,
        },
        Sensor::Rgbd(n) => n.pixel_noise(camera.rig.fx),
    }
}

impl Odometry {
    /// A stereo odometry for `camera` with the default robust estimator.
    ///
    /// # Errors
    /// [`OdometryError::Camera`] for a camera that is not valid.
    pub fn new(camera: StereoCamera, config: OdometryConfig) -> Result<Self, OdometryError> {
        Self::builder(camera).config(config).build()
    }

    /// A builder, for another estimator or an RGB-D camera.
    pub fn builder(camera: StereoCamera) -> OdometryBuilder {
        OdometryBuilder {
            camera,
            config: OdometryConfig::default(),
            estimator: None,
            rgbd: None,
        }
    }

    /// The camera (for RGB-D, with the virtual baseline).
    #[must_use]
    pub fn camera(&self) -> &StereoCamera {
        &self.camera
    }

    /// The camera of the images the engine works on: [`Odometry::camera`], halved while
    /// its images have more than [`OdometryConfig::max_working_pixels`] pixels and doubled
    /// while they have fewer than [`OdometryConfig::min_working_pixels`]. Everything else
    /// the engine reports in pixels is in pixels of [`Odometry::camera`].
    #[must_use]
    pub fn working_camera(&self) -> &StereoCamera {
        &self.working_camera
    }

    /// How the stereo images are resampled before any work: halved this many times when
    /// positive, doubled `−levels` times when negative, 0 for the images as they are.
    #[must_use]
    pub fn working_levels(&self) -> i32 {
        self.scale.levels
    }

    /// The detector's name.
    #[must_use]
    pub fn detector(&self) -> &'static str {
        match &self.inner {
            Inner::Orb(..) => swarmpose_vision::frontend::Detector::Orb.name(),
            Inner::Surf(..) => swarmpose_vision::frontend::Detector::Surf.name(),
        }
    }

    /// The estimator's name.
    #[must_use]
    pub fn estimator(&self) -> &'static str {
        with_inner!(&self.inner, _f, t => t.estimator_name())
    }

    /// The self-calibration's current decision and its evidence, in pixels of the
    /// camera's images (whatever the working size).
    #[must_use]
    pub fn calibration(&self) -> Decision {
        let d = with_inner!(&self.inner, _f, t => *t.calibration());
        self.scale.decision_in_camera_pixels(d)
    }

    /// The disparity correction applied to the next frame (pixels) and where it comes
    /// from: the self-calibration's current decision ([`Odometry::calibration`]),
    /// [`crate::CorrectionModel::GIVEN`] for a fixed correction, or none.
    #[must_use]
    pub fn correction(
        &self,
    ) -> (
        swarmpose_vision::frontend::DisparityCorrection,
        crate::CorrectionModel,
    ) {
        let (c, model) = with_inner!(&self.inner, _f, t => t.correction());
        (self.scale.correction_in_camera_pixels(c), model)
    }

    /// Heap bytes of the engine's per-frame state (the reference frame's features): it
    /// does not grow with the number of frames.
    #[must_use]
    pub fn state_bytes(&self) -> usize {
        with_inner!(&self.inner, _f, t => t.state_bytes())
            + self
                .resampled
                .iter()
                .map(Resampler::heap_bytes)
                .sum::<usize>()
    }

    /// Takes the next stereo frame and returns its pose. `load_ms` is the caller's time
    /// to obtain the images (reported in the stage times; 0 if not measured).
    ///
    /// # Errors
    /// [`OdometryError::Frame`] for images that do not fit the camera (size, empty, left
    /// and right different), left and right images that look exchanged (few stereo
    /// matches, and many with the images the other way round), or a timestamp that does
    /// not increase; the engine's state is then unchanged and the next frame can be
    /// given. [`OdometryError::Camera`] for
    /// an RGB-D engine.
    pub fn track(&mut self, input: StereoInput<'_>) -> Result<FrameResult, OdometryError> {
        self.track_timed(input, 0.0)
    }

    /// [`Odometry::track`] with the caller's loading time, milliseconds.
    ///
    /// # Errors
    /// As [`Odometry::track`].
    pub fn track_timed(
        &mut self,
        input: StereoInput<'_>,
        load_ms: f64,
    ) -> Result<FrameResult, OdometryError> {
        if self.sensor != Sensor::Stereo {
            return Err(OdometryError::Camera {
                message: "this engine takes RGB-D frames (track_rgbd), not stereo pairs".into(),
            });
        }
        let last = with_inner!(&self.inner, _f, t => t.last_timestamp_s());
        check_stereo(&self.camera, &input, last)?;
        let mut times = StageTimes {
            load_ms,
            ..StageTimes::default()
        };
        let t0 = std::time::Instant::now();
        let (left, right) = match self.scale.levels {
            0 => (input.left, input.right),
            levels => {
                let [l, r] = &mut self.resampled;
                (l.apply(input.left, levels), r.apply(input.right, levels))
            }
        };
        // Resampling is part of getting the images (stage time `load`).
        times.load_ms += crate::frontend::ms(t0);
        let scale = self.scale;
        with_inner!(&mut self.inner, f, t => {
            let frame = stereo_frame(f.as_ref(), left, right, &mut times)?;
            t.track(frame, Some(left), input.timestamp_s, times)
        })
        .map(|r| scale.result_in_camera_pixels(r))
    }

    /// Takes the next RGB-D frame and returns its pose.
    ///
    /// # Errors
    /// As [`Odometry::track`]; [`OdometryError::Camera`] for a stereo engine.
    pub fn track_rgbd(&mut self, input: RgbdInput<'_>) -> Result<FrameResult, OdometryError> {
        self.track_rgbd_timed(input, 0.0)
    }

    /// [`Odometry::track_rgbd`] with the caller's loading time, milliseconds.
    ///
    /// # Errors
    /// As [`Odometry::track_rgbd`].
    pub fn track_rgbd_timed(
        &mut self,
        input: RgbdInput<'_>,
        load_ms: f64,
    ) -> Result<FrameResult, OdometryError> {
        let Sensor::Rgbd(noise) = self.sensor else {
            return Err(OdometryError::Camera {
                message: "this engine takes stereo pairs (track), not RGB-D frames".into(),
            });
        };
        let last = with_inner!(&self.inner, _f, t => t.last_timestamp_s());
        check_rgbd(&self.camera, &input, last)?;
        let mut times = StageTimes {
            load_ms,
            ..StageTimes::default()
        };
        let rig = self.camera.rig;
        with_inner!(&mut self.inner, f, t => {
            let frame = rgbd_frame(f.as_ref(), &rig, &noise, input.gray, input.depth, &mut times);
            t.track(frame, Some(input.gray), input.timestamp_s, times)
        })
    }
}

/// A stereo frame whose images the caller owns, for [`Odometry::run_two_threads`].
#[derive(Debug, Clone)]
pub struct OwnedStereoFrame {
    /// Left image.
    pub left: GrayImage,
    /// Right image.
    pub right: GrayImage,
    /// Timestamp, seconds (strictly increasing along the stream).
    pub timestamp_s: f64,
    /// The caller's time to obtain the images, milliseconds (0 if not measured).
    pub load_ms: f64,
}

/// How a run over a stream of frames ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum RunEnd {
    /// Every frame was processed.
    Finished,
    /// `on_frame` asked to stop after this many frames.
    Stopped(usize),
}

impl Odometry {
    /// Runs the stereo frames of `frames` through the engine on two threads: while the
    /// back end (estimate, refinement, self-calibration, window) works on frame `k`, a
    /// second thread obtains frame `k + 1` (the iterator runs there), runs its front end
    /// (features, stereo matching) and matches it to frame `k` (unless the matching is
    /// guided by the back end's prediction; the back end matches again when its reference
    /// is another frame). The results are those of [`Odometry::track`] called frame by
    /// frame (the front end and an unguided matching do not depend on the back end's state),
    /// and reach `on_frame` in order, each as soon as it exists; `on_frame` may stop the
    /// run by returning [`ControlFlow::Break`]. Returns how the run ended.
    ///
    /// # Errors
    /// The error of the first frame that the iterator could not give or the engine could
    /// not take, at its 0-based position in `frames` ([`RunFailure::at_frame`]); the
    /// frames before it were given to `on_frame`. [`OdometryError::Camera`] for an RGB-D
    /// engine.
    pub fn run_two_threads<I, E>(
        &mut self,
        frames: I,
        on_frame: &mut dyn FnMut(&FrameResult) -> ControlFlow<()>,
    ) -> Result<RunEnd, E>
    where
        I: Iterator<Item = Result<OwnedStereoFrame, E>> + Send,
        E: RunFailure,
    {
        if self.sensor != Sensor::Stereo {
            return Err(OdometryError::Camera {
                message: "this engine takes RGB-D frames (track_rgbd), not stereo pairs".into(),
            }
            .into());
        }
        let camera = self.camera;
        let scale = self.scale;
        let levels = scale.levels;
        with_inner!(&mut self.inner, f, t => {
            let frontend = f.as_ref();
            let prematching = t.prematching();
            std::thread::scope(|scope| {
                // One frame in flight between the threads: memory stays bounded.
                let (tx, rx) = std::sync::mpsc::sync_channel(1);
                scope.spawn(move || {
                    let mut resamplers = [Resampler::default(), Resampler::default()];
                    let mut ahead = MatchAhead::new(prematching);
                    for (index, item) in frames.enumerate() {
                        let front = item.and_then(|frame| {
                            owned_front_end(frontend, &camera, levels, &mut resamplers, frame)
                                .map_err(E::from)
                        });
                        let front = front.map(|(features, frame, times)| {
                            let prematched = ahead.next(&features, frame.timestamp_s);
                            (features, frame, times, prematched)
                        });
                        let failed = front.is_err();
                        let message = front.map_err(|e| e.at_frame(index));
                        // A closed channel: the back end stopped.
                        if tx.send(message).is_err() || failed {
                            break;
                        }
                    }
                });
                let mut taken = 0;
                for message in rx {
                    let (features, frame, times, prematched) = message?;
                    let left = Some(frame.left.view());
                    let r = t
                        .track_prematched(features, left, frame.timestamp_s, times, prematched)
                        .map(|r| scale.result_in_camera_pixels(r))
                        .map_err(|e| E::from(e).at_frame(taken))?;
                    taken += 1;
                    if on_frame(&r).is_break() {
                        return Ok(RunEnd::Stopped(taken));
                    }
                }
                Ok(RunEnd::Finished)
            })
        })
    }
}

/// The temporal matching of [`Odometry::run_two_threads`], done ahead on the front end's
/// thread: each frame is matched to the last one with enough stereo points to become the
/// tracker's reference (the tracker's own rule), so that the back end finds its matches
/// ready. The back end checks that they are with its reference and matches again
/// otherwise ([`Prematched`]).
struct MatchAhead<D> {
    /// The matching's configuration and the fewest points of a reference; `None`: no
    /// matching ahead (a guided search needs the back end's prediction).
    prematching: Option<(TemporalConfig, usize)>,
    /// The last frame that can be the reference, and its timestamp (seconds).
    reference: Option<(StereoFrame<D>, f64)>,
}

impl<D: Descriptor> MatchAhead<D> {
    fn new(prematching: Option<(TemporalConfig, usize)>) -> Self {
        Self {
            prematching,
            reference: None,
        }
    }

    /// The matches of `frame` (taken at `timestamp_s`) with the expected reference, if
    /// any; `frame` becomes the next expected reference when it has enough points.
    fn next(&mut self, frame: &StereoFrame<D>, timestamp_s: f64) -> Option<Prematched> {
        let (temporal, min) = self.prematching?;
        if frame.len() < min {
            // Not tracked, and not the next reference.
            return None;
        }
        let prematched = self.reference.as_ref().and_then(|(reference, at_s)| {
            let t0 = std::time::Instant::now();
            // An error is found again, and reported, by the back end.
            let matches = match_frames(reference, frame, &temporal).ok()?;
            Some(Prematched {
                reference_timestamp_s: *at_s,
                matches,
                match_ms: crate::frontend::ms(t0),
            })
        });
        self.reference = Some((frame.clone(), timestamp_s));
        prematched
    }
}

/// The front end of a frame of [`Odometry::run_two_threads`] from `camera`: its images
/// resampled `levels` times (the left one into the frame's own buffer: the back end
/// takes the working left image for the tracks' patches), then its features and stereo
/// matches. Returns them with the frame and its stage times. The timestamp's order is
/// checked by the back end.
fn owned_front_end<E: FeatureExtractor>(
    frontend: &Frontend<E>,
    camera: &StereoCamera,
    levels: i32,
    [hl, hr]: &mut [Resampler; 2],
    mut frame: OwnedStereoFrame,
) -> Result<(StereoFrame<E::Descriptor>, OwnedStereoFrame, StageTimes), OdometryError> {
    let input = StereoInput {
        left: frame.left.view(),
        right: frame.right.view(),
        timestamp_s: frame.timestamp_s,
    };
    check_stereo(camera, &input, None)?;
    let mut times = StageTimes {
        load_ms: frame.load_ms,
        ..StageTimes::default()
    };
    if levels != 0 {
        let t0 = std::time::Instant::now();
        let l = hl.apply(frame.left.view(), levels);
        // Into the frame's own buffer: no allocation when halving.
        frame.left.data.clear();
        frame.left.data.extend_from_slice(l.data);
        (frame.left.width, frame.left.height) = (l.width, l.height);
        let r = hr.apply(frame.right.view(), levels);
        times.load_ms += crate::frontend::ms(t0);
        let features = stereo_frame(frontend, frame.left.view(), r, &mut times)?;
        return Ok((features, frame, times));
    }
    let features = stereo_frame(frontend, frame.left.view(), frame.right.view(), &mut times)?;
    Ok((features, frame, times))
}
