//! The odometry engine's settings as Python keyword arguments, shared by
//! `swarmpose.Odometry(...)`, `Odometry.from_sequence`, `Odometry.rgbd` and
//! `swarmpose.odometry`.

use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;
use swarmpose_odometry::config::Calibration;
use swarmpose_odometry::frontend::RgbdNoise;
use swarmpose_odometry::window::Marginalisation;
use swarmpose_odometry::{CorrectionModel, OdometryConfig, StereoCamera};
use swarmpose_vision::frontend::Detector;

use crate::errors::odometry_error;
use crate::methods;

/// The engine's settings as keyword arguments (defaults: those of
/// [`OdometryConfig::default`] and of the command line).
pub(crate) struct Options<'a> {
    pub(crate) method: &'a str,
    pub(crate) threshold: Option<f64>,
    pub(crate) detector: &'a str,
    pub(crate) refine: bool,
    pub(crate) calibrate: Option<&'a str>,
    pub(crate) disparity_correction: Option<(f64, f64)>,
    pub(crate) min_inliers: Option<usize>,
    pub(crate) seed: u64,
    /// Keyframes of the sliding window (0: frame to frame; `None`: the engine's default).
    pub(crate) window: Option<usize>,
    /// What happens to the window's oldest keyframe when it leaves (`None`: the engine's
    /// default, `"off"`).
    pub(crate) marginalise: Option<&'a str>,
    /// Most pixels of a stereo image the engine works on (`None`: the engine's default).
    pub(crate) max_working_pixels: Option<usize>,
    /// Fewest pixels of a stereo image the engine works on (`None`: the engine's default).
    pub(crate) min_working_pixels: Option<usize>,
    /// An RGB-D camera with this depth noise (frames go to `track_rgbd`).
    pub(crate) rgbd: Option<RgbdNoise>,
}

impl Options<'_> {
    fn config(&self) -> PyResult<OdometryConfig> {
        let detector: Detector =
            self.detector
                .parse()
                .map_err(|e: swarmpose_vision::frontend::UnknownDetector| {
                    PyValueError::new_err(e.to_string())
                })?;
        let mut c = OdometryConfig {
            detector,
            refine: self.refine,
            seed: self.seed,
            ..OdometryConfig::default()
        };
        if let Some(k) = self.window {
            c = c.with_window(k);
        }
        if let Some(mode) = self.marginalise {
            let mode: Marginalisation = mode
                .parse()
                .map_err(|e: String| PyValueError::new_err(format!("marginalise {e}")))?;
            c = c.with_marginalisation(mode);
        }
        if let Some(n) = self.max_working_pixels {
            c.max_working_pixels = n;
        }
        if let Some(n) = self.min_working_pixels {
            c.min_working_pixels = n;
        }
        if let Some(n) = self.min_inliers {
            if n < 3 {
                return Err(PyValueError::new_err(format!(
                    "min_inliers {n}: at least 3 are needed for a motion"
                )));
            }
            c.min_inliers = n;
        }
        let causes = match self.calibrate {
            Some(text) => CorrectionModel::parse(text).map_err(PyValueError::new_err)?,
            None => c.selfcal.candidates,
        };
        c.selfcal.candidates = causes;
        let (offset, quadratic) = self.disparity_correction.unzip();
        c.calibration = Calibration::from_options(
            causes,
            offset,
            quadratic,
            [
                "disparity_correction offset",
                "disparity_correction quadratic",
            ],
        )
        .map_err(PyValueError::new_err)?;
        Ok(c)
    }

    pub(crate) fn build(&self, camera: StereoCamera) -> PyResult<swarmpose_odometry::Odometry> {
        let config = self.config()?;
        let estimator = methods::estimator(self.method, self.threshold)?;
        let mut builder = swarmpose_odometry::Odometry::builder(camera)
            .config(config)
            .estimator(estimator);
        if let Some(noise) = self.rgbd {
            builder = builder.rgbd(noise);
        }
        builder.build().map_err(|e| odometry_error(&e))
    }
}
