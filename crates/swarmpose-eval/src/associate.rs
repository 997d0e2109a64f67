//! Pairing the poses of an estimate with those of a ground truth: by index (KITTI
//! files, one pose per frame) or by nearest timestamp within a tolerance (TUM files),
//! the same rule as evo's `associate_trajectories`.

use nalgebra::Isometry3;

use crate::error::EvalError;
use crate::trajectory::Trajectory;

/// evo's default tolerance of timestamp association, seconds.
pub const DEFAULT_MAX_DIFF_S: f64 = 0.01;

/// Paired poses: `estimate[k]` and `ground_truth[k]` belong to the same frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Associated {
    /// Estimated poses.
    pub estimate: Vec<Isometry3<f64>>,
    /// Ground-truth poses.
    pub ground_truth: Vec<Isometry3<f64>>,
    /// Timestamp of each pair (the estimate's).
    pub stamps: Vec<f64>,
}

impl Associated {
    /// Number of pairs.
    #[must_use]
    pub fn len(&self) -> usize {
        self.estimate.len()
    }

    /// True when nothing was paired.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.estimate.is_empty()
    }
}

/// Pairs by index: both trajectories must have the same number of poses.
///
/// # Errors
/// [`EvalError::LengthMismatch`] naming both trajectories and their lengths.
pub fn by_index(estimate: &Trajectory, ground_truth: &Trajectory) -> Result<Associated, EvalError> {
    if estimate.len() != ground_truth.len() {
        return Err(EvalError::LengthMismatch {
            estimate: estimate.name.clone(),
            n_estimate: estimate.len(),
            ground_truth: ground_truth.name.clone(),
            n_ground_truth: ground_truth.len(),
        });
    }
    Ok(Associated {
        estimate: estimate.poses.clone(),
        ground_truth: ground_truth.poses.clone(),
        stamps: estimate.stamps.clone(),
    })
}

/// Pairs by timestamp as evo does: each pose of the shorter trajectory is paired with
/// the nearest-in-time pose of the longer one when they are at most `max_diff_s` apart.
///
/// # Errors
/// [`EvalError::TooFew`] when fewer than 2 pairs are found.
pub fn by_timestamp(
    estimate: &Trajectory,
    ground_truth: &Trajectory,
    max_diff_s: f64,
) -> Result<Associated, EvalError> {
    let gt_longer = ground_truth.len() > estimate.len();
    let (short, long) = if gt_longer {
        (estimate, ground_truth)
    } else {
        (ground_truth, estimate)
    };
    let mut out = Associated {
        estimate: Vec::new(),
        ground_truth: Vec::new(),
        stamps: Vec::new(),
    };
    for (i, &t) in short.stamps.iter().enumerate() {
        let Some((j, d)) = long
            .stamps
            .iter()
            .map(|s| (s - t).abs())
            .enumerate()
            .min_by(|a, b| a.1.total_cmp(&b.1))
        else {
            continue;
        };
        if d <= max_diff_s {
            let (e, g) = if gt_longer { (i, j) } else { (j, i) };
            out.estimate.push(estimate.poses[e]);
            out.ground_truth.push(ground_truth.poses[g]);
            out.stamps.push(estimate.stamps[e]);
        }
    }
    if out.len() < 2 {
        return Err(EvalError::TooFew {
            what: format!(
                "timestamps of {} matched to {} within {max_diff_s} s",
                estimate.name, ground_truth.name
            ),
            got: out.len(),
            needed: 2,
        });
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::Vector3;

    fn traj(name: &str, stamps: &[f64]) -> Trajectory {
        Trajectory {
            stamps: stamps.to_vec(),
            poses: stamps
                .iter()
                .map(|&t| Isometry3::translation(t, 0.0, 0.0))
                .collect(),
            name: name.into(),
        }
    }

    #[test]
    fn index_needs_equal_lengths() {
        let a = traj("est", &[0.0, 1.0, 2.0]);
        let b = traj("gt", &[0.0, 1.0]);
        let e = by_index(&a, &b).expect_err("3 vs 2");
        assert!(
            e.to_string().contains("est has 3 poses but gt has 2"),
            "{e}"
        );
        assert_eq!(by_index(&a, &a).expect("same").len(), 3);
    }

    #[test]
    fn timestamps_nearest_within_tolerance() {
        let est = traj("est", &[1.0, 1.1, 1.2, 5.0]);
        let gt = traj("gt", &[0.995, 1.0, 1.005, 1.104, 1.3, 4.0]);
        let a = by_timestamp(&est, &gt, 0.01).expect("pairs");
        // est 1.0 -> gt 1.0, est 1.1 -> gt 1.104; 1.2 and 5.0 have none within 10 ms.
        assert_eq!(a.len(), 2);
        assert_eq!(a.stamps, vec![1.0, 1.1]);
        assert!(
            (a.ground_truth[1].translation.vector - Vector3::new(1.104, 0.0, 0.0)).norm() < 1e-12
        );
        let far = traj("far", &[10.0, 11.0]);
        assert!(by_timestamp(&far, &gt, 0.01).is_err());
    }
}
