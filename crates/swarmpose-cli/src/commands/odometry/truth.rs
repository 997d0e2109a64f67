//! `swarmpose odometry --ground-truth FILE`: the left camera's true poses from a file, in
//! place of the ground truth the sequence carries (a bag has none; a fleet's recordings
//! keep theirs beside them).
//!
//! KITTI poses (12 numbers a line, the row-major 3x4 `[R | t]` of the left camera in a
//! world frame) are one per frame, in order: the file must hold exactly as many poses as
//! the sequence has frames (a poses file of another sequence is refused, never cut to
//! fit). TUM poses (`timestamp tx ty tz qx qy qz qw`, seconds) are matched to each frame by
//! its absolute time, which only a bag records (its header stamps): the nearest pose within
//! [`DEFAULT_MAX_DIFF_S`] of every frame, or an error naming the first frame without one.
//! The format follows the file's name as in `swarmpose evaluate` (`*.tum.txt`, `*.tum` or
//! `groundtruth.txt`: TUM; anything else: KITTI). Either way the poses are re-based on the
//! first frame's: pose `i` is `P₀⁻¹ Pᵢ`, the left camera of frame `i` in that of frame 0,
//! metres, as every sequence's own ground truth is.

use std::path::Path;

use nalgebra::Isometry3;
use swarmpose_eval::associate::DEFAULT_MAX_DIFF_S;
use swarmpose_eval::{Format, Trajectory};

use crate::error::CliError;

/// The ground truth of `n_frames` frames read from `path`; `stamps_ns` are the frames'
/// absolute times in nanoseconds (a bag's header stamps), empty when the input has none.
///
/// # Errors
/// Exit status 2 naming the file: unreadable or malformed, a KITTI file with another
/// number of poses than frames, a TUM file for an input without absolute times, a frame
/// with no pose near its time.
pub fn read(
    path: &Path,
    n_frames: usize,
    stamps_ns: &[i64],
) -> Result<Vec<Isometry3<f64>>, CliError> {
    let format = Format::guess(path);
    let truth = Trajectory::read(path, format)
        .map_err(|e| CliError::usage(format!("--ground-truth: {e}")))?;
    let poses = match format {
        Format::Kitti => {
            if truth.len() != n_frames {
                return Err(CliError::usage(format!(
                    "--ground-truth {}: {} KITTI pose(s) for a sequence of {n_frames} frames: \
                     KITTI poses are one a frame, in order (is it another sequence's?)",
                    path.display(),
                    truth.len()
                )));
            }
            truth.poses
        }
        Format::Tum => by_time(path, &truth, n_frames, stamps_ns)?,
    };
    let first_inv = poses[0].inverse();
    Ok(poses.iter().map(|p| first_inv * p).collect())
}

/// The TUM pose nearest each frame's time, within [`DEFAULT_MAX_DIFF_S`].
fn by_time(
    path: &Path,
    truth: &Trajectory,
    n_frames: usize,
    stamps_ns: &[i64],
) -> Result<Vec<Isometry3<f64>>, CliError> {
    if stamps_ns.len() != n_frames {
        return Err(CliError::usage(format!(
            "--ground-truth {}: TUM poses are matched by time, and only a bag's frames carry \
             absolute times: give KITTI poses (one a frame, in order) for a sequence folder",
            path.display()
        )));
    }
    if truth.stamps.windows(2).any(|w| w[1] < w[0]) {
        return Err(CliError::usage(format!(
            "--ground-truth {}: the TUM timestamps are not in increasing order",
            path.display()
        )));
    }
    let mut poses = Vec::with_capacity(n_frames);
    for (k, &ns) in stamps_ns.iter().enumerate() {
        let t = ns as f64 * 1e-9;
        let j = truth.stamps.partition_point(|&s| s < t);
        let nearest = [j.checked_sub(1), Some(j)]
            .into_iter()
            .flatten()
            .filter(|&i| i < truth.len())
            .min_by(|&a, &b| {
                (truth.stamps[a] - t)
                    .abs()
                    .total_cmp(&(truth.stamps[b] - t).abs())
            });
        match nearest {
            Some(i) if (truth.stamps[i] - t).abs() <= DEFAULT_MAX_DIFF_S => {
                poses.push(truth.poses[i]);
            }
            _ => {
                return Err(CliError::usage(format!(
                    "--ground-truth {}: frame {k} (time {t:.6} s) has no pose within \
                     {DEFAULT_MAX_DIFF_S} s (the poses cover {:.6} to {:.6} s)",
                    path.display(),
                    truth.stamps.first().copied().unwrap_or(f64::NAN),
                    truth.stamps.last().copied().unwrap_or(f64::NAN)
                )));
            }
        }
    }
    Ok(poses)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn write(dir: &Path, name: &str, text: &str) -> std::path::PathBuf {
        let p = dir.join(name);
        std::fs::write(&p, text).expect("write");
        p
    }

    #[test]
    fn kitti_poses_are_rebased_on_the_first_and_must_match_the_frames() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = write(
            dir.path(),
            "poses.txt",
            "1 0 0 5 0 1 0 0 0 0 1 0\n1 0 0 6 0 1 0 0 0 0 1 2\n",
        );
        let poses = read(&p, 2, &[]).expect("two poses");
        assert!((poses[0].translation.vector.norm()) < 1e-12);
        assert!(
            (poses[1].translation.vector - nalgebra::Vector3::new(1.0, 0.0, 2.0)).norm() < 1e-12
        );
        let e = read(&p, 3, &[]).expect_err("three frames");
        assert_eq!(e.code, 2);
        assert!(
            e.message
                .contains("2 KITTI pose(s) for a sequence of 3 frames"),
            "{}",
            e.message
        );
    }

    #[test]
    fn tum_poses_are_matched_by_the_frames_times() {
        let dir = tempfile::tempdir().expect("tempdir");
        let p = write(
            dir.path(),
            "truth.tum.txt",
            "100.000 0 0 0 0 0 0 1\n100.050 1 0 0 0 0 0 1\n100.100 2 0 0 0 0 0 1\n",
        );
        let ns = |s: f64| (s * 1e9).round() as i64;
        let poses = read(&p, 2, &[ns(100.001), ns(100.099)]).expect("matched");
        assert!((poses[1].translation.vector.x - 2.0).abs() < 1e-12);
        let e = read(&p, 2, &[ns(100.0), ns(100.2)]).expect_err("no pose near 100.2 s");
        assert!(
            e.message
                .contains("frame 1 (time 100.200000 s) has no pose"),
            "{}",
            e.message
        );
        let e = read(&p, 2, &[]).expect_err("a folder has no absolute times");
        assert!(e.message.contains("give KITTI poses"), "{}", e.message);
    }
}
