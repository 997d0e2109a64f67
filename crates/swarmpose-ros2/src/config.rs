//! The engine's settings.

use std::path::Path;

use swarmpose_odometry::OdometryConfig;

use crate::error::NodeError;

/// The engine's settings for a run: those of a recorded run configuration (`--config
/// FILE`, the `config.json` every `swarmpose odometry` run writes), else the defaults.
///
/// THE ONE PLACE where the node loads its configuration. Until swarmpose-runs has its
/// loader of a recorded run configuration into an [`OdometryConfig`], a `--config` is
/// refused (rather than silently ignored) and the defaults are used without one; call
/// that loader here when it lands.
///
/// # Errors
/// [`NodeError::Usage`] for `--config` (not yet readable).
pub fn load_config(file: Option<&Path>) -> Result<OdometryConfig, NodeError> {
    match file {
        None => Ok(OdometryConfig::default()),
        Some(path) => Err(NodeError::Usage(format!(
            "--config {}: reading a recorded run configuration is not available in this \
             build yet; run without --config for the default settings",
            path.display()
        ))),
    }
}

/// The settings as printed at start, one line.
#[must_use]
pub fn settings_line(config: &OdometryConfig) -> String {
    format!("{config:?}")
}
