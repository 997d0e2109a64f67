//! Settings of the odometry engine, with their defaults. One default configuration
//! serves every sequence: nothing here is chosen for one data set.

use swarmpose_core::EstimatorConfig;
use swarmpose_core::settings::{
    InvalidSetting, at_least_zero, count_at_least, positive, positive_or_infinite,
};
use swarmpose_vision::frontend::{
    Detector, DisparityCorrection, OrbFrontendConfig, SurfFrontendConfig,
};

use crate::refine::RefineConfig;
use crate::refine::floor::FloorConfig;
use crate::refine::model::PixelNoise;
use crate::selfcal::{CorrectionModel, SelfCalConfig};
use crate::window::WindowConfig;

/// How the disparity correction of the stereo calibration is obtained.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(rename_all = "snake_case")
)]
pub enum Calibration {
    /// Chosen online by evidence ([`crate::selfcal`]): no correction, or any of a constant
    /// offset, a quadratic term and a term linear in `x` (the causes of
    /// [`CorrectionModel::DEFAULT_CANDIDATES`]), whichever the held-out pairs support;
    /// updated as frames arrive (default).
    #[default]
    Auto,
    /// The rig's calibration as given: no correction.
    Off,
    /// A fixed correction.
    Fixed(DisparityCorrection),
}

/// Largest magnitude of a fixed disparity correction term, pixels: real corrections are
/// fractions of a pixel to a few pixels; beyond this the points would be placed at depths
/// that have nothing to do with the images (an offset of 1e9 px puts every point at the
/// camera and every motion at the identity).
pub const MAX_FIXED_CORRECTION_PX: f64 = 100.0;

/// Fewest inliers [`OdometryConfig::min_inliers`] may ask for: a rigid motion needs
/// three points that are not collinear.
pub const MIN_INLIERS: usize = 3;

impl Calibration {
    /// The mode a user's options ask for: the `causes` self-calibration may correct, and
    /// a fixed correction's offset and quadratic term (pixels; either may be given),
    /// whose option names `names` the messages use. As [`Calibration::from_terms`]
    /// without a linear term.
    ///
    /// # Errors
    /// As [`Calibration::from_terms`].
    pub fn from_options(
        causes: CorrectionModel,
        offset_px: Option<f64>,
        quadratic_px: Option<f64>,
        names: [&str; 2],
    ) -> Result<Self, String> {
        Self::from_terms(
            causes,
            [offset_px, quadratic_px, None],
            [names[0], names[1], "linear term"],
        )
    }

    /// The mode a user's options ask for: the `causes` self-calibration may correct, and
    /// a fixed correction's terms `[offset, quadratic, linear_x]` (pixels, the
    /// coefficients of `1`, `x²` and `x` in [`DisparityCorrection`]; any may be given),
    /// whose option names `names` the messages use. A fixed correction wins; no causes
    /// and no fixed correction is [`Calibration::Off`].
    ///
    /// # Errors
    /// A term that is not finite or is larger than [`MAX_FIXED_CORRECTION_PX`].
    pub fn from_terms(
        causes: CorrectionModel,
        terms_px: [Option<f64>; 3],
        names: [&str; 3],
    ) -> Result<Self, String> {
        for (name, v) in names.iter().zip(terms_px) {
            if v.is_some_and(|d| !d.is_finite()) {
                return Err(format!("{name} must be a finite number of pixels"));
            }
            if let Some(d) = v.filter(|d| d.abs() > MAX_FIXED_CORRECTION_PX) {
                return Err(format!(
                    "{name} {d:e} px is outside -{MAX_FIXED_CORRECTION_PX}..\
                     {MAX_FIXED_CORRECTION_PX} px: a disparity correction is a few pixels at most"
                ));
            }
        }
        Ok(match terms_px {
            [None, None, None] if causes == CorrectionModel::NONE => Self::Off,
            [None, None, None] => Self::Auto,
            [a, q, l] => Self::Fixed(DisparityCorrection {
                offset_px: a.unwrap_or(0.0),
                quadratic_px: q.unwrap_or(0.0),
                linear_x_px: l.unwrap_or(0.0),
                ..DisparityCorrection::default()
            }),
        })
    }
}

/// Settings of [`crate::Odometry`]: every setting of the engine, its front end's and its
/// estimator's included, with their defaults. One default configuration serves every
/// sequence. With the `serde` feature it is what a run configuration file holds (see
/// `swarmpose_runs::config`); a file may give only the settings it changes.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct OdometryConfig {
    /// Detector and descriptor of the front end (default ORB).
    pub detector: Detector,
    /// Settings of the ORB front end (used with [`Detector::Orb`]).
    pub orb: OrbFrontendConfig,
    /// Settings of the SURF front end (used with [`Detector::Surf`]).
    pub surf: SurfFrontendConfig,
    /// The robust estimator of each motion and its settings (default the robust PSO,
    /// `pso`); [`crate::OdometryBuilder::estimator`] may give one of another kind.
    pub estimator: EstimatorConfig,
    /// Refine each motion on the reprojection error in both images ([`crate::refine`])
    /// (default true). Without it the estimator's motion is used as it is and no
    /// covariance is given.
    pub refine: bool,
    /// The disparity correction (default [`Calibration::Auto`]).
    pub calibration: Calibration,
    /// Fewest inliers for a motion to be accepted (default 12; at least
    /// [`MIN_INLIERS`], checked when the engine is made).
    pub min_inliers: usize,
    /// Seed of the estimator: frame `k` uses `seed + k` (default 0).
    pub seed: u64,
    /// Longest time, seconds, over which a lost motion is predicted at constant
    /// velocity; after it the frame is marked lost and the pose held (default 1.0).
    pub max_prediction_s: f64,
    /// Standard deviations of the stereo measurements; `None` takes the front end's
    /// (default `None`).
    pub pixel_noise: Option<PixelNoise>,
    /// Settings of the reprojection refinement.
    pub refinement: RefineConfig,
    /// Settings of the self-calibration.
    pub selfcal: SelfCalConfig,
    /// The sliding window of keyframes refined together (default: 10 keyframes,
    /// [`WindowConfig::default`]).
    pub window: WindowConfig,
    /// Most pixels of a stereo image the engine works on: larger images are halved
    /// (2x2 means) until they have at most this many, before any other work (default
    /// 1 500 000: 1280x1024 stays as it is, 1920x1080 is halved once; `usize::MAX`: never;
    /// at least 10 000). The front end's windows, descriptors and noise are in pixels of a
    /// camera of about half a megapixel to a megapixel ([`crate::working`]); what the
    /// engine reports stays in pixels of the camera's images
    /// ([`crate::Odometry::working_camera`] is the working one). RGB-D frames are never
    /// resampled.
    pub max_working_pixels: usize,
    /// Fewest pixels of a stereo image the engine works on: smaller images are doubled
    /// (bicubic, as SIFT doubles its input) until they have at least this many (default
    /// 0: never; at most a quarter of the maximum, and at most
    /// [`crate::working::MAX_MIN_WORKING_PIXELS`]). Not the default, because it helps some
    /// measurements and hurts others (RESULTS.md, "Other image sizes"): with 250 000,
    /// kitti_vo_seq2 at half size (620x188) ends 1.148 % instead of 1.986 % and the
    /// built-in street (480x288) 0.010 % instead of 0.039 %, but the street's
    /// self-calibration finds a right camera's yaw 16 % short (4 % at its own size)
    /// and the still EuRoC clip (752x480, with 375 000) wanders 0.61 mm instead of 0.26 mm.
    pub min_working_pixels: usize,
    /// Run the split-feature check of each pair's covariance (default false: it costs two
    /// more refinements a frame): [`FrameResult::split`](crate::FrameResult::split),
    /// [`crate::refine::split`]. Its NEES is judged with the systematic floor when that is
    /// on ([`crate::refine::split::SplitCheck::model_nees`] is the model's alone).
    pub split_check: bool,
    /// The systematic floor added to every reported covariance: errors shared at the
    /// scale of half the image, learned online from the split-feature check of the
    /// frames before ([`crate::refine::floor`]; default on, which runs that check on
    /// every refined pair).
    pub covariance_floor: FloorConfig,
}

impl OdometryConfig {
    /// The same settings with a sliding window of `keyframes` keyframes
    /// ([`crate::window`]; 0 to 2: frame to frame only).
    #[must_use]
    pub fn with_window(mut self, keyframes: usize) -> Self {
        self.window.keyframes = keyframes;
        self
    }

    /// The same settings with the window's oldest keyframe marginalised as `mode` says
    /// when it leaves ([`crate::window::marginal`]).
    #[must_use]
    pub fn with_marginalisation(mut self, mode: crate::window::Marginalisation) -> Self {
        self.window.marginalise = mode;
        self
    }

    /// Checks the range of every setting, the estimator's included (the working-size band
    /// and the camera are checked with the camera): a value
    /// outside its range, such as a negative tolerance or noise sigma, is an error naming
    /// the setting by its path in a run configuration (`orb.stereo.row_tolerance_px`).
    ///
    /// # Errors
    /// [`crate::OdometryError::Config`] naming the setting.
    pub fn check(&self) -> Result<(), crate::OdometryError> {
        if self.min_inliers < MIN_INLIERS {
            return Err(crate::OdometryError::Config {
                message: format!(
                    "min_inliers {}: at least {MIN_INLIERS} are needed for a motion",
                    self.min_inliers
                ),
            });
        }
        let floor = &self.covariance_floor;
        if floor.memory_frames == 0
            || !(floor.significance.is_finite() && floor.significance >= 0.0)
        {
            return Err(crate::OdometryError::Config {
                message: format!(
                    "covariance_floor: memory_frames {} (at least 1) and significance {} \
                     (finite, at least 0)",
                    floor.memory_frames, floor.significance
                ),
            });
        }
        let named = |e: InvalidSetting| crate::OdometryError::Config {
            message: e.to_string(),
        };
        self.orb.check("orb").map_err(named)?;
        self.surf.check("surf").map_err(named)?;
        self.estimator.check("estimator").map_err(named)?;
        self.check_engine_ranges().map_err(named)
    }

    /// The ranges of the engine's own settings (the refinements, the self-calibration,
    /// the prediction), named by their path in a run configuration.
    fn check_engine_ranges(&self) -> Result<(), InvalidSetting> {
        let r = &self.refinement;
        positive("refinement.huber_k", r.huber_k)?;
        positive("refinement.gate_chi2", r.gate_chi2)?;
        positive("refinement.initial_gate_chi2", r.initial_gate_chi2)?;
        positive(
            "refinement.align_max_move_px",
            f64::from(r.align_max_move_px),
        )?;
        let c = &self.selfcal;
        at_least_zero("selfcal.margin", c.margin)?;
        count_at_least("selfcal.stripes", c.stripes, 2)?;
        positive("selfcal.max_sigma_px", c.max_sigma_px)?;
        positive("selfcal.max_focal_sigma", c.max_focal_sigma)?;
        positive_or_infinite("selfcal.memory_s", c.memory_s)?;
        at_least_zero("selfcal.min_off_plane_sigmas", c.min_off_plane_sigmas)?;
        positive("window.huber_k", self.window.huber_k)?;
        at_least_zero("max_prediction_s", self.max_prediction_s)?;
        Ok(())
    }
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            detector: Detector::default(),
            orb: OrbFrontendConfig::default(),
            surf: SurfFrontendConfig::default(),
            estimator: EstimatorConfig::default(),
            refine: true,
            calibration: Calibration::default(),
            min_inliers: 12,
            seed: 0,
            max_prediction_s: 1.0,
            pixel_noise: None,
            refinement: RefineConfig::default(),
            selfcal: SelfCalConfig::default(),
            window: WindowConfig::default(),
            max_working_pixels: 1_500_000,
            min_working_pixels: 0,
            split_check: false,
            covariance_floor: FloorConfig::default(),
        }
    }
}
