//! The engine's settings.

use std::path::Path;

use swarmpose_odometry::OdometryConfig;
use swarmpose_runs::config::RunConfig;

use crate::error::NodeError;

/// The engine's settings for a run: those of a recorded run configuration (`--config
/// FILE`, the `config.json` every `swarmpose odometry` run writes; its `odometry`
/// part), else the defaults.
///
/// # Errors
/// [`NodeError::Usage`] for a configuration file that cannot be read or used, with the
/// message of [`swarmpose_runs::config::RunConfig::read`].
pub fn load_config(file: Option<&Path>) -> Result<OdometryConfig, NodeError> {
    match file {
        None => Ok(OdometryConfig::default()),
        Some(path) => RunConfig::read(path)
            .map(|c| c.odometry)
            .map_err(|e| NodeError::Usage(e.to_string())),
    }
}

/// The settings as printed at start, one line.
#[must_use]
pub fn settings_line(config: &OdometryConfig) -> String {
    format!("{config:?}")
}
