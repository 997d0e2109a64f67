//! The configuration of a run: every setting of the engine (its front end's and
//! estimator's included, [`OdometryConfig`]) and of the run around it (how frames are
//! read, how outputs are named), with their defaults in one place.
//!
//! Every run writes it as `config.json` beside its outputs, before its first frame;
//! `swarmpose odometry --config FILE` (and Python's `config=`) reads it back, so the run
//! can be repeated exactly: the same file and the same input give the same trajectory,
//! byte for byte. A file may give only the settings it changes: the others keep their
//! defaults. A setting it does not know is an error, so a misspelt name never goes
//! unnoticed.
//!
//! ```json
//! { "format": "swarmpose-config/1",
//!   "odometry": { "window": { "keyframes": 5 }, "estimator": { "method": "msac" } } }
//! ```

use std::path::{Path, PathBuf};

use serde::{Deserialize, Serialize};
use swarmpose_odometry::OdometryConfig;

use crate::error::RunError;

/// The longest frame period, seconds (11.6 days): frame times are `i × period`, and a
/// period of 1e308 made the second frame's time infinite ("timestamp inf").
pub const MAX_FRAME_PERIOD_S: f64 = 1e6;

/// The format tag of a configuration file (and its version).
pub const FORMAT: &str = "swarmpose-config/1";

/// The name of the configuration file a run writes beside its outputs.
pub const FILE_NAME: &str = "config.json";

/// The settings of a run.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct RunConfig {
    /// [`FORMAT`]: a file of another format or version is refused.
    pub format: String,
    /// The engine's settings.
    pub odometry: OdometryConfig,
    /// How frames are read.
    pub input: InputConfig,
    /// How the outputs name things.
    pub output: OutputConfig,
    /// Threads: 1, or 2 to read and run the front end of the next frame while the back
    /// end works on this one (the same trajectory; stereo sequences only).
    pub threads: u8,
}

/// How the frames of a sequence are read.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct InputConfig {
    /// Seconds between frames of a sequence without timestamps (default 0.1).
    pub frame_period_s: f64,
    /// ROS 2 bag: the left image topic (`None`: found).
    pub left_topic: Option<String>,
    /// ROS 2 bag: the right image topic (`None`: found).
    pub right_topic: Option<String>,
    /// ROS 2 bag: the depth image topic of an RGB-D input (`None`: found when the bag has
    /// one colour and one depth camera); with it, `left_topic` names the colour topic.
    pub depth_topic: Option<String>,
    /// ROS 2 bag: largest difference of the header stamps of a left and a right image
    /// paired into a frame, milliseconds (default 0: equal stamps).
    pub stamp_tolerance_ms: f64,
}

impl Default for InputConfig {
    fn default() -> Self {
        Self {
            frame_period_s: 0.1,
            left_topic: None,
            right_topic: None,
            depth_topic: None,
            stamp_tolerance_ms: 0.0,
        }
    }
}

/// How the outputs name things.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct OutputConfig {
    /// The fixed frame of the poses in the ROS 2 messages (default `odom`).
    pub odom_frame: String,
    /// The camera frame of the ROS 2 messages (`None`: the images' `frame_id` from a
    /// bag, else `camera_optical`).
    pub camera_frame: Option<String>,
    /// Every how many frames `odometry.mcap` carries the left image with the inliers
    /// drawn (`sensor_msgs/CompressedImage`, PNG) and the inliers' points
    /// (`sensor_msgs/PointCloud2`, metres, camera frame): frames 0, N, 2N, ... (0: none).
    pub mcap_images: usize,
}

impl Default for OutputConfig {
    fn default() -> Self {
        Self {
            odom_frame: "odom".into(),
            camera_frame: None,
            mcap_images: 0,
        }
    }
}

impl Default for RunConfig {
    fn default() -> Self {
        Self {
            format: FORMAT.into(),
            odometry: OdometryConfig::default(),
            input: InputConfig::default(),
            output: OutputConfig::default(),
            threads: 1,
        }
    }
}

impl RunConfig {
    /// Reads a configuration file and checks it ([`RunConfig::check`]).
    ///
    /// # Errors
    /// [`RunError::Config`]: the file cannot be read, is not JSON, names a setting
    /// that does not exist, has a value of the wrong type, is of another format, or
    /// holds a value out of its range.
    pub fn read(path: &Path) -> Result<Self, RunError> {
        let error = |message: String| RunError::Config {
            path: path.to_owned(),
            message,
        };
        let text = std::fs::read_to_string(path).map_err(|e| error(e.to_string()))?;
        Self::from_json(&text).map_err(|e| match e {
            RunError::Config { message, .. } => error(message),
            other => other,
        })
    }

    /// The configuration of a JSON text (as [`RunConfig::read`]; errors name no file).
    ///
    /// # Errors
    /// As [`RunConfig::read`].
    pub fn from_json(text: &str) -> Result<Self, RunError> {
        let error = |message: String| RunError::Config {
            path: PathBuf::new(),
            message,
        };
        // A UTF-8 byte-order mark is accepted, as by every reader.
        let text = text.strip_prefix('\u{feff}').unwrap_or(text);
        let config: Self = serde_json::from_str(text).map_err(|e| error(e.to_string()))?;
        if config.format != FORMAT {
            return Err(error(format!(
                "format {:?}: this swarmpose reads {FORMAT:?}",
                config.format
            )));
        }
        config.check().map_err(error)?;
        Ok(config)
    }

    /// The configuration as pretty JSON, ending with a newline: every setting, the
    /// defaults included, in a fixed order.
    ///
    /// # Errors
    /// [`RunError::Config`] for a value JSON cannot hold (a number that is not finite).
    pub fn to_json(&self) -> Result<String, RunError> {
        let mut text = serde_json::to_string_pretty(self).map_err(|e| RunError::Config {
            path: PathBuf::new(),
            message: e.to_string(),
        })?;
        // serde_json writes a number that is not finite as null, which does not read
        // back as a number: refuse it here rather than write a file that cannot be rerun.
        if Self::from_json(&text).ok().as_ref() != Some(self) {
            return Err(RunError::Config {
                path: PathBuf::new(),
                message: "a setting has a value a configuration file cannot hold \
                          (a number that is not finite)"
                    .into(),
            });
        }
        text.push('\n');
        Ok(text)
    }

    /// Checks the settings of the run and those of the engine that have a range of
    /// their own ([`OdometryConfig::check`]; the engine checks the rest against the
    /// camera).
    ///
    /// # Errors
    /// A message naming the setting.
    pub fn check(&self) -> Result<(), String> {
        self.odometry.check().map_err(|e| e.to_string())?;
        let input = &self.input;
        if !(input.frame_period_s > 0.0 && input.frame_period_s <= MAX_FRAME_PERIOD_S) {
            return Err(format!(
                "input.frame_period_s must be a positive number of seconds, at most \
                 {MAX_FRAME_PERIOD_S:e} (a frame's time i x period overflowed to inf)"
            ));
        }
        if !(input.stamp_tolerance_ms.is_finite() && input.stamp_tolerance_ms >= 0.0) {
            return Err(
                "input.stamp_tolerance_ms must be a number of milliseconds, 0 or more".into(),
            );
        }
        if !(1..=2).contains(&self.threads) {
            return Err(format!("threads {}: 1 or 2", self.threads));
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_default_configuration_reads_back_as_written() {
        let c = RunConfig::default();
        let text = c.to_json().expect("json");
        assert_eq!(RunConfig::from_json(&text).expect("reads"), c);
        let with_bom = format!("\u{feff}{text}");
        assert_eq!(
            RunConfig::from_json(&with_bom).expect("a BOM is accepted"),
            c
        );
    }

    #[test]
    fn an_endless_calibration_memory_is_written_as_inf() {
        let mut c = RunConfig::default();
        c.odometry.selfcal.memory_s = f64::INFINITY;
        let text = c.to_json().expect("json");
        assert!(text.contains(r#""memory_s": "inf""#), "{text}");
        assert_eq!(RunConfig::from_json(&text).expect("reads"), c);
    }

    #[test]
    fn a_file_gives_only_what_it_changes() {
        let c = RunConfig::from_json(
            r#"{"format": "swarmpose-config/1",
                "odometry": {"window": {"keyframes": 5}, "estimator": {"method": "msac"}}}"#,
        )
        .expect("reads");
        assert_eq!(c.odometry.window.keyframes, 5);
        assert_eq!(c.odometry.estimator.method(), swarmpose_core::Method::Msac);
        assert_eq!(
            c.odometry.min_inliers,
            OdometryConfig::default().min_inliers
        );
    }

    #[test]
    fn unknown_settings_other_formats_and_bad_values_are_refused() {
        let bad = [
            (r#"{"odometry": {"windw": {}}}"#, "unknown field `windw`"),
            (
                r#"{"format": "swarmpose-config/9"}"#,
                "this swarmpose reads",
            ),
            (r#"{"odometry": {"min_inliers": 2}}"#, "min_inliers 2"),
            (r#"{"input": {"frame_period_s": -1}}"#, "frame_period_s"),
            (r#"{"input": {"frame_period_s": 1e308}}"#, "at most 1e6"),
            (r#"{"threads": 3}"#, "threads 3"),
            (
                r#"{"odometry": {"estimator": {"method": "ransac"}}}"#,
                "unknown variant",
            ),
            ("[", "EOF"),
        ];
        for (text, expected) in bad {
            let e = RunConfig::from_json(text).expect_err(text).to_string();
            assert!(e.contains(expected), "{text}: {e}");
        }
    }
}
