//! `swarmpose odometry --split-check`: each tracked pair's split-feature check of its
//! covariance ([`swarmpose_odometry::refine::split`]) in `split_check.csv`, and its mean
//! and median in the summary.

use swarmpose_odometry::FrameResult;

use super::output::{OutputDir, StreamFile};
use crate::error::CliError;

/// The header of `split_check.csv`.
pub const SPLIT_HEADER: &str = "# Each tracked pair's motion refined again on the left and \
on the right half of its inliers (split at their median column): nees = d' (C1 + C2)^-1 d \
of the difference d = (nu, omega) of the two motions (metres, radians, current camera), with \
C1 + C2 widened by the systematic floor learned from the frames before (6 on average when the \
covariance is honest); inliers of each half; model_nees: the same under C1 + C2 alone.\n\
frame,nees,d_nu_x,d_nu_y,d_nu_z,d_omega_x,d_omega_y,d_omega_z,inliers_left,inliers_right,\
model_nees";

/// `split_check.csv`, written frame by frame, and the figures of the summary.
pub struct SplitLog {
    file: StreamFile,
    nees: Vec<f64>,
}

impl SplitLog {
    /// Creates `split_check.csv` in `dir`.
    ///
    /// # Errors
    /// The file cannot be created.
    pub fn create(dir: &OutputDir) -> Result<Self, CliError> {
        Ok(Self {
            file: StreamFile::create(dir, "split_check.csv", Some(SPLIT_HEADER))?,
            nees: Vec::new(),
        })
    }

    /// Adds the frame's check, when it has one.
    ///
    /// # Errors
    /// The line cannot be written.
    pub fn add(&mut self, r: &FrameResult) -> Result<(), CliError> {
        let Some(s) = &r.split else {
            return Ok(());
        };
        let d = &s.difference;
        self.nees.push(s.nees);
        let mut row = vec![r.index.to_string(), format!("{:.6}", s.nees)];
        row.extend(d.iter().map(|v| format!("{v:e}")));
        row.extend(s.inliers.map(|n| n.to_string()));
        row.push(format!("{:.6}", s.model_nees));
        Ok(self.file.record(row)?)
    }

    /// The summary line: mean and median NEES over the pairs checked.
    #[must_use]
    pub fn summary(&self) -> String {
        if self.nees.is_empty() {
            return "split-feature check: no pair had enough inliers in both halves".into();
        }
        let mut v = self.nees.clone();
        v.sort_by(f64::total_cmp);
        let median = if v.len() % 2 == 1 {
            v[v.len() / 2]
        } else {
            0.5 * (v[v.len() / 2 - 1] + v[v.len() / 2])
        };
        let mean = v.iter().sum::<f64>() / v.len() as f64;
        format!(
            "split-feature check: mean NEES {mean:.2}, median {median:.2} over {} pairs (6 when \
             the covariance is honest)",
            v.len()
        )
    }
}
