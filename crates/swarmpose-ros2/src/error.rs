//! Errors of the node, each one line.

/// Why the node cannot start or go on.
#[derive(Debug, thiserror::Error)]
pub enum NodeError {
    /// A bad option or environment variable (exit status 2).
    #[error("{0}")]
    Usage(String),
    /// DDS could not be set up (a participant, a topic, a reader or a writer).
    #[error("DDS: {0}")]
    Dds(String),
    /// The engine refused the camera or a setting, or failed on a frame.
    #[error(transparent)]
    Engine(#[from] swarmpose_odometry::OdometryError),
    /// An output could not be written (exit status 1).
    #[error(transparent)]
    Run(#[from] swarmpose_runs::RunError),
    /// `odometry.mcap` could not be written (exit status 1).
    #[error(transparent)]
    Ros(#[from] swarmpose_ros::RosError),
}

impl NodeError {
    /// The process's exit status for this error.
    #[must_use]
    pub fn exit_status(&self) -> u8 {
        match self {
            Self::Usage(_) => 2,
            Self::Run(e) if e.is_input() => 2,
            _ => 1,
        }
    }

    /// A DDS error (RustDDS's errors are shown with their details).
    pub fn dds(what: &str, e: impl std::fmt::Debug) -> Self {
        Self::Dds(format!("{what}: {e:?}"))
    }
}
