//! The images of a bag that found no partner when left and right were paired: they are
//! in no frame, and are never dropped silently. Each gets a row of `frames.csv` (no frame
//! number, its time from the first frame, status `unpaired (TOPIC message I, stamp NS ns)`,
//! the other columns empty) in time order among the frames, and the run's summary counts
//! and names them.

use std::collections::VecDeque;

use swarmpose_ros::stereo::pairing::UnpairedImage;
use swarmpose_runs::output::FRAMES_HEADER;

use super::output::StreamFile;
use crate::error::CliError;

/// Most unpaired images named in the summary line (all are in `frames.csv`).
const NAMED_IN_SUMMARY: usize = 5;

/// The unpaired images of a run, written into `frames.csv` as the frames pass them.
pub struct Unpaired {
    pending: VecDeque<UnpairedImage>,
    all: Vec<UnpairedImage>,
    /// The first frame's header stamp, nanoseconds (time 0 of `frames.csv`).
    first_stamp_ns: i64,
}

/// The `frames.csv` row of an unpaired image whose stamp is `t` seconds from the first
/// frame's.
fn row(u: &UnpairedImage, t: f64) -> Vec<String> {
    let mut row = vec![String::new(), format!("{t:.6}"), format!("unpaired ({u})")];
    row.resize(FRAMES_HEADER.split(',').count(), String::new());
    row
}

impl Unpaired {
    /// The unpaired images of a bag (in stamp order) whose first frame has the header
    /// stamp `first_stamp_ns`.
    #[must_use]
    pub fn new(images: &[UnpairedImage], first_stamp_ns: i64) -> Self {
        Self {
            pending: images.iter().cloned().collect(),
            all: images.to_vec(),
            first_stamp_ns,
        }
    }

    /// Writes the rows of the images older than `stamp_ns` (the next frame's stamp;
    /// `i64::MAX` for all that are left).
    ///
    /// # Errors
    /// Exit status 1 when `frames.csv` cannot be written.
    pub fn write_before(&mut self, stamp_ns: i64, frames: &mut StreamFile) -> Result<(), CliError> {
        while self.pending.front().is_some_and(|u| u.stamp_ns < stamp_ns) {
            if let Some(u) = self.pending.pop_front() {
                let t = (u.stamp_ns - self.first_stamp_ns) as f64 * 1e-9;
                frames.record(row(&u, t)).map_err(CliError::from)?;
            }
        }
        Ok(())
    }

    /// The summary's words: how many images found no partner and which, or `None`.
    #[must_use]
    pub fn summary(&self) -> Option<String> {
        let n = self.all.len();
        if n == 0 {
            return None;
        }
        let named: Vec<String> = self
            .all
            .iter()
            .take(NAMED_IN_SUMMARY)
            .map(ToString::to_string)
            .collect();
        let more = if n > NAMED_IN_SUMMARY {
            format!(" and {} more", n - NAMED_IN_SUMMARY)
        } else {
            String::new()
        };
        Some(format!(
            "{n} image(s) without a partner, in no frame: {}{more} (rows 'unpaired' of frames.csv)",
            named.join(", ")
        ))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unpaired_row_has_every_column() {
        let u = UnpairedImage {
            topic: "/right/image".to_owned(),
            message: 3,
            stamp_ns: 1_500_000_000,
        };
        let r = swarmpose_runs::output::csv_record(row(&u, 0.5)).expect("a record");
        assert_eq!(r.split(',').count(), FRAMES_HEADER.split(',').count());
        assert!(r.starts_with(",0.500000,unpaired (/right/image message 3 (stamp 1500000000 ns))"));
    }
}
