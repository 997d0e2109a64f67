//! Settings of the odometry engine, with their defaults. One default configuration
//! serves every sequence: nothing here is chosen for one data set.

use swarmpose_vision::frontend::{Detector, DisparityCorrection};

use crate::refine::RefineConfig;
use crate::refine::model::PixelNoise;
use crate::selfcal::SelfCalConfig;
use crate::window::WindowConfig;

/// How the disparity correction of the stereo calibration is obtained.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum Calibration {
    /// Chosen online by evidence ([`crate::selfcal`]): no correction, a constant offset or
    /// an offset plus a quadratic term, whichever the held-out pairs support; updated as
    /// frames arrive (default).
    #[default]
    Auto,
    /// The rig's calibration as given: no correction.
    Off,
    /// A fixed correction.
    Fixed(DisparityCorrection),
}

/// Settings of [`crate::Odometry`].
#[derive(Debug, Clone, PartialEq)]
pub struct OdometryConfig {
    /// Detector and descriptor of the front end (default ORB).
    pub detector: Detector,
    /// Refine each motion on the reprojection error in both images ([`crate::refine`])
    /// (default true). Without it the estimator's motion is used as it is and no
    /// covariance is given.
    pub refine: bool,
    /// The disparity correction (default [`Calibration::Auto`]).
    pub calibration: Calibration,
    /// Fewest inliers for a motion to be accepted (default 12).
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
    /// The sliding window of keyframes refined together (default: none).
    pub window: WindowConfig,
}

impl Default for OdometryConfig {
    fn default() -> Self {
        Self {
            detector: Detector::default(),
            refine: true,
            calibration: Calibration::default(),
            min_inliers: 12,
            seed: 0,
            max_prediction_s: 1.0,
            pixel_noise: None,
            refinement: RefineConfig::default(),
            selfcal: SelfCalConfig::default(),
            window: WindowConfig::default(),
        }
    }
}
