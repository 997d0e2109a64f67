//! Options of the stereo front end and its disparity correction, shared by `odometry`
//! and `correspondences`.

use clap::Args;
use swarmpose_odometry::CorrectionModel;
use swarmpose_odometry::config::Calibration;
use swarmpose_odometry::selfcal::SelfCalConfig;
use swarmpose_vision::frontend::Detector;

use crate::error::CliError;

fn parse_detector(s: &str) -> Result<Detector, String> {
    s.parse::<Detector>().map_err(|e| e.to_string())
}

fn detector_help() -> String {
    let names: Vec<String> = Detector::ALL
        .iter()
        .map(|d| format!("{} ({})", d.name(), d.description()))
        .collect();
    format!("Detector and descriptor: {}", names.join("; "))
}

fn parse_causes(s: &str) -> Result<CorrectionModel, String> {
    CorrectionModel::parse(s)
}

/// The front end's detector and the disparity correction.
#[derive(Debug, Clone, Args)]
pub struct StereoOptions {
    #[arg(long, value_name = "NAME", default_value = "orb", value_parser = parse_detector,
          help = detector_help())]
    pub detector: Detector,

    /// A fixed disparity correction instead of self-calibration: its constant term,
    /// pixels (added to every measured disparity; at most 100 in magnitude).
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    pub disparity_offset: Option<f64>,

    /// A fixed disparity correction: its term in x², pixels, with x = (u - d - cx) / f
    /// the right image column (a yaw of the right camera); with --disparity-offset
    /// (default 0); at most 100 in magnitude.
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    pub disparity_quadratic: Option<f64>,

    /// A fixed disparity correction: its term in x, pixels, with x as for
    /// --disparity-quadratic (a focal length of the right camera that is off); with
    /// --disparity-offset (default 0); at most 100 in magnitude.
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    pub disparity_linear: Option<f64>,

    /// The causes of a disparity error that self-calibration may correct, when they have
    /// evidence: `none` (no correction), or some of principal-point (a constant, seen as
    /// a scene that is not rigid between frames), yaw, roll, pitch (seen in the rows of
    /// each stereo pair), focal (the right camera's: a term linear in x, by rigidity) and
    /// focal-length (the rig's, both cameras: seen when the camera turns; not a default,
    /// see docs/self-calibration.md), joined by '+'.
    #[arg(long, value_name = "CAUSES", default_value_t = CorrectionModel::DEFAULT_CANDIDATES,
          value_parser = parse_causes)]
    pub calibrate: CorrectionModel,

    /// Time constant, seconds, with which the self-calibration's evidence of past frame
    /// pairs fades, or `inf` to keep all of it.
    #[arg(long, value_name = "S", default_value_t = SelfCalConfig::default().memory_s,
          value_parser = parse_memory)]
    pub calibration_memory: f64,
}

fn parse_memory(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v > 0.0 && !v.is_nan() => Ok(v),
        _ => Err(format!(
            "'{s}' is not a positive number of seconds (or inf)"
        )),
    }
}

impl StereoOptions {
    /// The engine's calibration mode and self-calibration settings.
    ///
    /// # Errors
    /// A fixed correction term that is not finite or too large
    /// ([`Calibration::from_options`]).
    pub fn calibration(&self) -> Result<(Calibration, SelfCalConfig), CliError> {
        let selfcal = SelfCalConfig {
            candidates: self.calibrate,
            memory_s: self.calibration_memory,
            ..SelfCalConfig::default()
        };
        let mode = Calibration::from_terms(
            self.calibrate,
            [
                self.disparity_offset,
                self.disparity_quadratic,
                self.disparity_linear,
            ],
            [
                "--disparity-offset",
                "--disparity-quadratic",
                "--disparity-linear",
            ],
        )
        .map_err(CliError::usage)?;
        Ok((mode, selfcal))
    }
}
