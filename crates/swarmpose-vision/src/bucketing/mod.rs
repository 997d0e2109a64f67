//! Bucketing: keep the strongest few features in each cell of a regular grid, so
//! features spread over the whole image instead of piling up on textured spots.

use crate::features::Keypoint;

/// Grid and quota of [`bucket_indices`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct BucketConfig {
    /// Cell width, pixels.
    pub cell_width: usize,
    /// Cell height, pixels.
    pub cell_height: usize,
    /// Most features kept per cell (the strongest by response).
    pub per_cell: usize,
}

impl Default for BucketConfig {
    fn default() -> Self {
        Self {
            cell_width: 48,
            cell_height: 48,
            per_cell: 10,
        }
    }
}

/// Indices of the keypoints kept: per cell, the `per_cell` largest responses (ties by
/// index). The result is sorted ascending. `width`/`height` are the image size, pixels.
#[must_use]
pub fn bucket_indices(
    keypoints: &[Keypoint],
    width: usize,
    height: usize,
    config: &BucketConfig,
) -> Vec<usize> {
    let mut kept = Vec::new();
    bucket_indices_into(
        keypoints,
        (width, height),
        config,
        &mut BucketScratch::default(),
        &mut kept,
    );
    kept
}

/// Buffers of [`bucket_indices_into`], reused between calls.
#[derive(Debug, Clone, Default)]
pub struct BucketScratch {
    cells: Vec<usize>,
    order: Vec<usize>,
}

/// [`bucket_indices`] into `kept` (cleared first), with buffers reused between calls.
pub fn bucket_indices_into(
    keypoints: &[Keypoint],
    (width, height): (usize, usize),
    config: &BucketConfig,
    scratch: &mut BucketScratch,
    kept: &mut Vec<usize>,
) {
    let cw = config.cell_width.max(1);
    let ch = config.cell_height.max(1);
    let cols = width.div_ceil(cw).max(1);
    let rows = height.div_ceil(ch).max(1);
    let cell_of = |k: &Keypoint| {
        let cx = ((k.x.max(0.0) as usize) / cw).min(cols - 1);
        let cy = ((k.y.max(0.0) as usize) / ch).min(rows - 1);
        cy * cols + cx
    };
    // Each keypoint's cell once (not in every comparison). The order is total (ties by
    // index), so an unstable sort gives the same order.
    let BucketScratch { cells, order } = scratch;
    cells.clear();
    cells.extend(keypoints.iter().map(cell_of));
    order.clear();
    order.extend(0..keypoints.len());
    order.sort_unstable_by(|&a, &b| {
        cells[a]
            .cmp(&cells[b])
            .then(keypoints[b].response.total_cmp(&keypoints[a].response))
            .then(a.cmp(&b))
    });
    kept.clear();
    kept.reserve(keypoints.len().min(cols * rows * config.per_cell));
    let mut current = usize::MAX;
    let mut count = 0;
    for &i in order.iter() {
        let c = cells[i];
        if c != current {
            current = c;
            count = 0;
        }
        if count < config.per_cell {
            kept.push(i);
            count += 1;
        }
    }
    kept.sort_unstable();
}

#[cfg(test)]
mod tests {
    use super::*;

    fn kp(x: f32, y: f32, response: f32) -> Keypoint {
        Keypoint {
            x,
            y,
            scale: 1.0,
            angle: 0.0,
            response,
            octave: 0,
        }
    }

    #[test]
    fn keeps_the_strongest_per_cell() {
        let kps = vec![
            kp(1.0, 1.0, 1.0),
            kp(2.0, 2.0, 3.0),
            kp(3.0, 3.0, 2.0),
            kp(15.0, 1.0, 0.5),
        ];
        let cfg = BucketConfig {
            cell_width: 10,
            cell_height: 10,
            per_cell: 2,
        };
        assert_eq!(bucket_indices(&kps, 20, 10, &cfg), vec![1, 2, 3]);
    }
}
