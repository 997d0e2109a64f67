//! Options of the stereo front end and its disparity correction, shared by `odometry`
//! and `correspondences`.

use clap::Args;
use swarmpose_odometry::CorrectionModel;
use swarmpose_odometry::OdometryConfig;
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
    format!(
        "Detector and descriptor: {} [default: {}]",
        names.join("; "),
        Detector::default().name()
    )
}

fn parse_causes(s: &str) -> Result<CorrectionModel, String> {
    CorrectionModel::parse(s)
}

/// The front end's detector and the disparity correction.
#[derive(Debug, Clone, Args)]
pub struct StereoOptions {
    #[arg(long, value_name = "NAME", value_parser = parse_detector, help = detector_help())]
    pub detector: Option<Detector>,

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
    #[arg(long, value_name = "CAUSES", value_parser = parse_causes, help = format!(
        "The causes of a disparity error that self-calibration may correct, when they have \
         evidence: none, or some of principal-point, yaw, roll, pitch, focal and \
         focal-length, joined by '+' (docs/self-calibration.md) [default: {}]",
        CorrectionModel::DEFAULT_CANDIDATES))]
    pub calibrate: Option<CorrectionModel>,

    /// Time constant, seconds, with which the self-calibration's evidence of past frame
    /// pairs fades, or `inf` to keep all of it.
    #[arg(long, value_name = "S", value_parser = parse_memory, help = format!(
        "Time constant, seconds, with which the self-calibration's evidence of past frame \
         pairs fades, or `inf` to keep all of it [default: {}]",
        SelfCalConfig::default().memory_s))]
    pub calibration_memory: Option<f64>,
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
    /// The detector asked for, or the default.
    pub fn detector(&self) -> Detector {
        self.detector.unwrap_or_default()
    }

    /// The engine's calibration mode and self-calibration settings from these options
    /// alone (over the defaults).
    pub fn calibration(&self) -> Result<(Calibration, SelfCalConfig), CliError> {
        let mut config = OdometryConfig::default();
        self.apply(&mut config)?;
        Ok((config.calibration, config.selfcal))
    }

    /// `config` with the options given applied over it: the detector; the causes the
    /// self-calibration may correct and its memory; a fixed correction, which wins over
    /// self-calibration. Without a fixed correction or `--calibrate`, the configuration's
    /// calibration mode stays as it is.
    pub fn apply(&self, config: &mut OdometryConfig) -> Result<(), CliError> {
        if let Some(d) = self.detector {
            config.detector = d;
        }
        if let Some(m) = self.calibration_memory {
            config.selfcal.memory_s = m;
        }
        let terms = [
            self.disparity_offset,
            self.disparity_quadratic,
            self.disparity_linear,
        ];
        if let Some(c) = self.calibrate {
            config.selfcal.candidates = c;
        }
        if self.calibrate.is_some() || terms.iter().any(Option::is_some) {
            config.calibration = Calibration::from_terms(
                config.selfcal.candidates,
                terms,
                [
                    "--disparity-offset",
                    "--disparity-quadratic",
                    "--disparity-linear",
                ],
            )
            .map_err(CliError::usage)?;
        }
        Ok(())
    }
}
