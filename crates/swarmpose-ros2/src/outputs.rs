//! `--out DIR`: the files `swarmpose odometry` writes as a run goes
//! ([`swarmpose_runs::output_dir::FrameFiles`] and `odometry.mcap`), frame by frame, so
//! that a node stopped at any point keeps whole lines and whole frames.

use std::path::Path;

use swarmpose_odometry::FrameResult;
use swarmpose_ros::msg::CameraInfo;
use swarmpose_ros::write::{FrameMessages, OdometryMcap};
use swarmpose_runs::output_dir::{FrameFiles, OutputDir};

use crate::error::NodeError;

/// The name of the MCAP file in the folder.
pub const MCAP: &str = "odometry.mcap";

/// A run's output folder.
pub struct RunFiles {
    _dir: OutputDir,
    files: FrameFiles,
    mcap: OdometryMcap,
}

impl RunFiles {
    /// Prepares `path` ([`OutputDir::prepare`]) and creates the files.
    ///
    /// # Errors
    /// [`NodeError::Run`] or [`NodeError::Ros`] naming what cannot be written.
    pub fn create(path: &Path) -> Result<Self, NodeError> {
        let dir = OutputDir::prepare(path)?;
        for note in dir.notes() {
            eprintln!("swarmpose-ros2: {note}");
        }
        let files = FrameFiles::create(&dir)?;
        let (file, mcap_path) = dir.create(MCAP)?;
        let mcap = OdometryMcap::new(file, &mcap_path)?;
        Ok(Self {
            _dir: dir,
            files,
            mcap,
        })
    }

    /// Writes the left camera's `camera_info`.
    ///
    /// # Errors
    /// [`NodeError::Ros`].
    pub fn camera_info(&mut self, info: &CameraInfo) -> Result<(), NodeError> {
        Ok(self.mcap.camera_info(info)?)
    }

    /// Writes one frame.
    ///
    /// # Errors
    /// [`NodeError::Run`] or [`NodeError::Ros`].
    pub fn frame(&mut self, r: &FrameResult, msg: &FrameMessages) -> Result<(), NodeError> {
        self.files.frame(r)?;
        Ok(self.mcap.frame(msg)?)
    }

    /// Writes the path and closes `odometry.mcap`.
    ///
    /// # Errors
    /// [`NodeError::Ros`].
    pub fn finish(self) -> Result<(), NodeError> {
        Ok(self.mcap.finish(None)?)
    }
}
