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
    starts: Vec<usize>,
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
    let BucketScratch {
        cells,
        starts,
        order,
    } = scratch;
    // The keypoints grouped by cell, each cell's indices ascending: a counting sort, or
    // a sort when the cells outnumber the keypoints (no buffer the size of a fine grid).
    cells.clear();
    cells.extend(keypoints.iter().map(cell_of));
    order.clear();
    let n_cells = cols * rows;
    if n_cells <= 2 * keypoints.len() + 64 {
        starts.clear();
        starts.resize(n_cells + 1, 0);
        for &c in cells.iter() {
            starts[c + 1] += 1;
        }
        for c in 0..n_cells {
            starts[c + 1] += starts[c];
        }
        order.resize(keypoints.len(), 0);
        for (i, &c) in cells.iter().enumerate() {
            order[starts[c]] = i;
            starts[c] += 1;
        }
    } else {
        order.extend(0..keypoints.len());
        order.sort_unstable_by_key(|&i| (cells[i], i));
    }
    // Each cell's `per_cell` first by response, descending (ties by index): a total
    // order, so the set selected is that of a full sort. The kept indices are sorted at
    // the end: their order within a cell does not matter.
    let stronger = |&a: &usize, &b: &usize| {
        keypoints[b]
            .response
            .total_cmp(&keypoints[a].response)
            .then(a.cmp(&b))
    };
    kept.clear();
    kept.reserve(keypoints.len().min(n_cells.saturating_mul(config.per_cell)));
    let mut start = 0;
    while let Some(&first) = order.get(start) {
        let cell = cells[first];
        let len = order[start..]
            .iter()
            .position(|&i| cells[i] != cell)
            .unwrap_or(order.len() - start);
        let run = &mut order[start..start + len];
        if len > config.per_cell && config.per_cell > 0 {
            run.select_nth_unstable_by(config.per_cell - 1, stronger);
        }
        kept.extend_from_slice(&run[..len.min(config.per_cell)]);
        start += len;
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

    /// [`bucket_indices_into`] as it was before issue 34: one sort by cell, response
    /// (descending) and index, then the first `per_cell` of each cell.
    fn bucket_by_sorting(kps: &[Keypoint], (w, h): (usize, usize), c: &BucketConfig) -> Vec<usize> {
        let (cw, ch) = (c.cell_width.max(1), c.cell_height.max(1));
        let (cols, rows) = (w.div_ceil(cw).max(1), h.div_ceil(ch).max(1));
        let cell_of = |k: &Keypoint| {
            let cx = ((k.x.max(0.0) as usize) / cw).min(cols - 1);
            let cy = ((k.y.max(0.0) as usize) / ch).min(rows - 1);
            cy * cols + cx
        };
        let mut order: Vec<usize> = (0..kps.len()).collect();
        order.sort_by(|&a, &b| {
            cell_of(&kps[a])
                .cmp(&cell_of(&kps[b]))
                .then(kps[b].response.total_cmp(&kps[a].response))
                .then(a.cmp(&b))
        });
        let (mut kept, mut current, mut count) = (Vec::new(), usize::MAX, 0);
        for i in order {
            if cell_of(&kps[i]) != current {
                (current, count) = (cell_of(&kps[i]), 0);
            }
            if count < c.per_cell {
                kept.push(i);
                count += 1;
            }
        }
        kept.sort_unstable();
        kept
    }

    /// [`bucket_indices_into`] keeps the indices of a full sort, on seeded random keypoints
    /// (inside, on and outside the image, NaN and tied responses of both signs, zeros of
    /// both signs), for quotas from none to more than any cell holds, with one scratch.
    #[test]
    fn selection_keeps_what_sorting_kept() {
        let noise = crate::test_noise::noise_bytes(4 * 3000, 41);
        let responses = [0.5, -0.5, 0.0, -0.0, f32::NAN, 1e-30, 7.0];
        let kps: Vec<Keypoint> = noise
            .chunks_exact(4)
            .map(|b| {
                let response = if b[2] < 64 {
                    responses[usize::from(b[3]) % responses.len()]
                } else {
                    f32::from(b[3]) - 100.0
                };
                kp(
                    f32::from(b[0]) * 0.9 - 20.0,
                    f32::from(b[1]) * 0.5 - 5.0,
                    response,
                )
            })
            .collect();
        let (mut scratch, mut kept) = (BucketScratch::default(), Vec::new());
        for (n, (w, h), (cw, ch), per_cell) in [
            (3000, (200, 120), (48, 48), 20),
            (3000, (200, 120), (48, 48), 1),
            (3000, (200, 120), (30, 20), 3),
            // More cells than keypoints: grouped by a sort.
            (3000, (200, 120), (0, 0), 2),
            (3000, (200, 120), (1, 2), 1),
            (3000, (50, 40), (10, 10), 0),
            (10, (200, 120), (48, 48), 5),
            (3000, (200, 120), (300, 300), 10_000),
            (0, (200, 120), (48, 48), 5),
        ] {
            let config = BucketConfig {
                cell_width: cw,
                cell_height: ch,
                per_cell,
            };
            let kps = &kps[..n];
            bucket_indices_into(kps, (w, h), &config, &mut scratch, &mut kept);
            let want = bucket_by_sorting(kps, (w, h), &config);
            assert_eq!(kept, want, "{config:?} {w}x{h}");
            assert!(n < 3000 || per_cell == 0 || kept.len() > 10, "{config:?}");
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
