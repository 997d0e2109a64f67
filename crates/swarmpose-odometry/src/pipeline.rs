//! The odometry pipeline: for every consecutive pair of frames, the stereo front end
//! (features, stereo matching and triangulation, temporal matching), the estimator on
//! the 3D-3D correspondences (with the per-point stereo noise), a Mahalanobis
//! refinement on the stereo covariances, and the chaining of eq. (2):
//! `C_{i+1} = C_i T_{i,i+1}`, where `T_{i,i+1}` is the motion `dst = R src + t` with
//! src the points of frame `i+1` and dst those of frame `i` (the pose of camera `i+1`
//! in camera `i`).
//!
//! The disparity offset of the stereo calibration is self-calibrated from the images
//! unless fixed ([`swarmpose_vision::frontend::calibrate_offset`]: the offset that makes
//! the moving pairs most rigid, by a robust Mahalanobis cost with covariances rescaled
//! with the points): kitti_vo_seq2's disparities are about 1.2 px short of its
//! calibration, which makes every translation about 6 % too long.
//!
//! A pair without a motion (the estimator fails, or fewer than
//! [`OdometryConfig::min_inliers`] inliers) is never given a silent identity: the
//! previous motion is repeated (constant velocity) and the frame is marked so.

use std::time::Instant;

use nalgebra::Isometry3;
use swarmpose_core::Estimator;
use swarmpose_core::geometry::chain;
use swarmpose_datasets::StereoSequence;
use swarmpose_vision::features::{Descriptor, FeatureExtractor};
use swarmpose_vision::frontend::{
    CHI2_3_99, DisparityCorrection, FrameMatches, Frontend, MIN_CALIBRATION_TRANSLATION_M,
    StereoFrame, calibrate_correction, calibrate_offset, match_frames, refine_stereo,
};
use swarmpose_vision::temporal::TemporalConfig;

use crate::error::OdometryError;

/// How the disparity correction is chosen.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DisparityOffset {
    /// Self-calibrated from the images: the constant plus quadratic
    /// [`DisparityCorrection`] that makes the moving pairs most rigid
    /// ([`calibrate_correction`]).
    SelfCalibrate,
    /// Self-calibrated constant offset only ([`swarmpose_vision::frontend::calibrate_offset`]).
    SelfCalibrateConstant,
    /// A fixed constant offset, pixels.
    Fixed(f64),
    /// A fixed correction.
    Correction(DisparityCorrection),
}

/// Settings of the pipeline (the front end and estimator are passed separately).
#[derive(Debug, Clone, PartialEq)]
pub struct OdometryConfig {
    /// Refine every motion on the stereo covariances (Mahalanobis).
    pub refine: bool,
    /// The disparity offset.
    pub disparity_offset: DisparityOffset,
    /// Fewest inliers for a motion to be accepted.
    pub min_inliers: usize,
    /// Seed of the estimator for pair `k` is `seed + k`.
    pub seed: u64,
    /// Seconds between frames (timestamps of the TUM output).
    pub frame_period_s: f64,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            refine: true,
            disparity_offset: DisparityOffset::SelfCalibrate,
            min_inliers: 12,
            seed: 0,
            frame_period_s: 0.1,
        }
    }
}

/// What happened to the motion into one frame.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Status {
    /// The first frame: no motion.
    First,
    /// Estimated.
    Ok,
    /// Not estimated: the previous motion repeated (constant velocity); the reason.
    ConstantVelocity(String),
}

impl Status {
    /// The text of frames.csv: `first`, `ok` or `constant-velocity (REASON)`.
    #[must_use]
    pub fn text(&self) -> String {
        match self {
            Status::First => "first".into(),
            Status::Ok => "ok".into(),
            Status::ConstantVelocity(why) => format!("constant-velocity ({why})"),
        }
    }
}

/// Wall-clock time of each stage for one frame, milliseconds.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct StageTimes {
    /// Loading (and rectifying) the images.
    pub load_ms: f64,
    /// Feature extraction in both images.
    pub features_ms: f64,
    /// Stereo matching and triangulation.
    pub stereo_ms: f64,
    /// Matching to the previous frame.
    pub match_ms: f64,
    /// The estimator.
    pub estimate_ms: f64,
    /// Offset calibration and refinement.
    pub refine_ms: f64,
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
    }
}

/// One frame of the log.
#[derive(Debug, Clone, PartialEq)]
pub struct FrameRecord {
    /// Frame index.
    pub frame: usize,
    /// Features detected in the left image.
    pub n_left_features: usize,
    /// Features detected in the right image.
    pub n_right_features: usize,
    /// Triangulated (stereo-matched) features.
    pub n_stereo: usize,
    /// 3D-3D correspondences with the previous frame.
    pub n_matches: usize,
    /// Inliers of the accepted motion (0 when none).
    pub n_inliers: usize,
    /// Motion status.
    pub status: Status,
    /// Stage times.
    pub times: StageTimes,
    /// The motion from the previous frame, `T_{i-1,i}` (identity for frame 0).
    pub motion: Isometry3<f64>,
}

/// A finished run.
#[derive(Debug, Clone)]
pub struct OdometryRun {
    /// Camera poses in the frame of camera 0, `C_0 = I`.
    pub poses: Vec<Isometry3<f64>>,
    /// Timestamps, seconds (frame index times the frame period).
    pub stamps: Vec<f64>,
    /// Per-frame log.
    pub frames: Vec<FrameRecord>,
    /// The disparity correction applied (its constant part is
    /// [`OdometryRun::disparity_offset_px`]).
    pub disparity_correction: DisparityCorrection,
    /// The disparity offset applied at the image centre, pixels.
    pub disparity_offset_px: f64,
    /// The estimator's name.
    pub method: String,
    /// The detector's name.
    pub detector: String,
}

impl OdometryRun {
    /// Frames marked constant-velocity.
    #[must_use]
    pub fn n_fallbacks(&self) -> usize {
        self.frames
            .iter()
            .filter(|f| matches!(f.status, Status::ConstantVelocity(_)))
            .count()
    }
}

fn ms(t: Instant) -> f64 {
    t.elapsed().as_secs_f64() * 1e3
}

/// The front-end output of one pair, before the estimator.
struct PairData {
    matches: Option<FrameMatches>,
}

/// Runs the pipeline on `seq`. `progress(done, total)` is called after every frame of
/// the front-end pass.
///
/// # Errors
/// [`OdometryError::TooFewFrames`] for fewer than 2 frames, dataset errors while
/// loading frames.
pub fn run<E: FeatureExtractor>(
    seq: &dyn StereoSequence,
    frontend: &Frontend<E>,
    estimator: &dyn Estimator,
    config: &OdometryConfig,
    progress: &mut dyn FnMut(usize, usize),
) -> Result<OdometryRun, OdometryError> {
    let n = seq.len();
    if n < 2 {
        return Err(OdometryError::TooFewFrames {
            dir: seq.root().to_owned(),
            n,
        });
    }
    let mut make_frame =
        |i: usize| -> Result<(StereoFrame<E::Descriptor>, StageTimes), OdometryError> {
            let mut times = StageTimes::default();
            let t = Instant::now();
            let pair = seq.frame(i)?;
            times.load_ms = ms(t);
            let t = Instant::now();
            let lf = frontend.extract(pair.left.view());
            let rf = frontend.extract_right(pair.right.view());
            times.features_ms = ms(t);
            let t = Instant::now();
            let frame =
                frontend.stereo_from_features(&lf, &rf, pair.left.view(), pair.right.view());
            times.stereo_ms = ms(t);
            Ok((frame, times))
        };
    let stamps: Vec<f64> = (0..n).map(|i| i as f64 * config.frame_period_s).collect();
    run_frames(
        n,
        &mut make_frame,
        &frontend.temporal,
        estimator,
        config,
        progress,
        stamps,
        frontend.extractor.name(),
    )
}

/// The pipeline on any source of triangulated frames: `make_frame(i)` gives frame `i`
/// and the time of its stages; `stamps` are the frames' timestamps.
///
/// # Errors
/// Whatever `make_frame` returns.
#[allow(clippy::too_many_arguments)]
pub fn run_frames<D: Descriptor>(
    n: usize,
    make_frame: &mut dyn FnMut(usize) -> Result<(StereoFrame<D>, StageTimes), OdometryError>,
    temporal: &TemporalConfig,
    estimator: &dyn Estimator,
    config: &OdometryConfig,
    progress: &mut dyn FnMut(usize, usize),
    stamps: Vec<f64>,
    detector: &str,
) -> Result<OdometryRun, OdometryError> {
    let mut frames: Vec<FrameRecord> = Vec::with_capacity(n);
    let mut pairs: Vec<PairData> = Vec::with_capacity(n.saturating_sub(1));
    let mut prev: Option<StereoFrame<D>> = None;
    // Pass 1: front end on every frame, estimator on every pair.
    let mut first_estimates: Vec<Option<Isometry3<f64>>> = Vec::new();
    let mut failures: Vec<Option<String>> = Vec::new();
    for i in 0..n {
        let (frame, times) = make_frame(i)?;
        let mut record = FrameRecord {
            frame: i,
            n_left_features: frame.n_left_features,
            n_right_features: frame.n_right_features,
            n_stereo: frame.len(),
            n_matches: 0,
            n_inliers: 0,
            status: Status::First,
            times,
            motion: Isometry3::identity(),
        };
        if let Some(p) = prev.take() {
            let t = Instant::now();
            let m = match_frames(&p, &frame, temporal);
            record.times.match_ms = ms(t);
            let k = i - 1;
            let t = Instant::now();
            let (m, est) = match m {
                Ok(m) => {
                    record.n_matches = m.correspondences.len();
                    let e = estimator
                        .estimate_seeded(&m.correspondences, config.seed.wrapping_add(k as u64));
                    (Some(m), e.map_err(|e| e.to_string()))
                }
                Err(e) => (None, Err(format!("matching failed: {e}"))),
            };
            record.times.estimate_ms = ms(t);
            match est {
                Ok(e) if e.inliers.len() >= config.min_inliers => {
                    record.n_inliers = e.inliers.len();
                    first_estimates.push(Some(e.transform));
                    failures.push(None);
                }
                Ok(e) => {
                    first_estimates.push(None);
                    failures.push(Some(format!(
                        "{} inliers, fewer than {}",
                        e.inliers.len(),
                        config.min_inliers
                    )));
                }
                Err(why) => {
                    first_estimates.push(None);
                    failures.push(Some(why));
                }
            }
            pairs.push(PairData { matches: m });
        }
        frames.push(record);
        prev = Some(frame);
        progress(i + 1, n);
    }

    // The disparity correction.
    let offset = match config.disparity_offset {
        DisparityOffset::Fixed(d) => DisparityCorrection::constant(d),
        DisparityOffset::Correction(c) => c,
        DisparityOffset::SelfCalibrate | DisparityOffset::SelfCalibrateConstant => {
            let t = Instant::now();
            let moving: Vec<(&FrameMatches, Isometry3<f64>)> = pairs
                .iter()
                .zip(&first_estimates)
                .filter_map(|(p, e)| Some((p.matches.as_ref()?, (*e)?)))
                // The offset is only observable from a translation.
                .filter(|(_, e)| e.translation.vector.norm() >= MIN_CALIBRATION_TRANSLATION_M)
                .collect();
            let correction = if config.disparity_offset == DisparityOffset::SelfCalibrate {
                calibrate_correction(&moving)
            } else {
                DisparityCorrection::constant(calibrate_offset(&moving))
            };
            let per_pair = ms(t) / pairs.len().max(1) as f64;
            for f in frames.iter_mut().skip(1) {
                f.times.refine_ms += per_pair;
            }
            correction
        }
    };

    // Pass 2: refinement with the offset, fallbacks, chaining.
    let mut motions: Vec<Isometry3<f64>> = Vec::with_capacity(n - 1);
    let mut last_good: Option<Isometry3<f64>> = None;
    for (k, (p, e)) in pairs.iter().zip(&first_estimates).enumerate() {
        let record = &mut frames[k + 1];
        let t = Instant::now();
        let mut outcome: Result<(Isometry3<f64>, usize), String> = match (e, &failures[k]) {
            (Some(e), _) => Ok((*e, record.n_inliers)),
            (None, Some(why)) => Err(why.clone()),
            (None, None) => Err("no estimate".into()),
        };
        if let Ok((start, _)) = outcome
            && (config.refine || offset != DisparityCorrection::default())
        {
            outcome = refined(p, &start, offset, config, estimator, k);
        }
        record.times.refine_ms += ms(t);
        let motion = match outcome {
            Ok((m, inliers)) => {
                record.n_inliers = inliers;
                record.status = Status::Ok;
                last_good = Some(m);
                m
            }
            Err(why) => {
                record.n_inliers = 0;
                match last_good {
                    Some(m) => {
                        record.status = Status::ConstantVelocity(why);
                        m
                    }
                    None => {
                        record.status = Status::ConstantVelocity(format!(
                            "{why}; no previous motion: identity"
                        ));
                        Isometry3::identity()
                    }
                }
            }
        };
        record.motion = motion;
        motions.push(motion);
    }
    let poses = chain(Isometry3::identity(), &motions);
    Ok(OdometryRun {
        stamps,
        poses,
        frames,
        disparity_correction: offset,
        disparity_offset_px: offset.offset_px,
        method: estimator.name().to_owned(),
        detector: detector.to_owned(),
    })
}

/// The motion of pair `p` refined with the disparity offset applied.
fn refined(
    p: &PairData,
    start: &Isometry3<f64>,
    offset: DisparityCorrection,
    config: &OdometryConfig,
    estimator: &dyn Estimator,
    k: usize,
) -> Result<(Isometry3<f64>, usize), String> {
    let Some(m) = &p.matches else {
        return Err("no matches".into());
    };
    let m = if offset == DisparityCorrection::default() {
        m.clone()
    } else {
        m.with_disparity_correction(offset)
            .map_err(|e| format!("disparity correction {offset}: {e}"))?
    };
    if !config.refine {
        // The estimator alone, again on the corrected points.
        let e = estimator
            .estimate_seeded(&m.correspondences, config.seed.wrapping_add(k as u64))
            .map_err(|e| e.to_string())?;
        return Ok((e.transform, e.inliers.len()));
    }
    let (pose, inliers) = refine_stereo(
        &m.correspondences,
        &m.src_covariances,
        &m.dst_covariances,
        start,
        CHI2_3_99,
        10,
    )
    .map_err(|e| format!("refinement: {e}"))?;
    if inliers.len() < config.min_inliers {
        return Err(format!(
            "{} inliers after refinement, fewer than {}",
            inliers.len(),
            config.min_inliers
        ));
    }
    Ok((pose, inliers.len()))
}
