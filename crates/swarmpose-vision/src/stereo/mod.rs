//! Stereo matching on a rectified pair: candidates on the same row (within a tolerance)
//! and inside a disparity range, best descriptor distance with a ratio test, left-right
//! consistency, sub-pixel disparity, and triangulation into the left camera frame.

mod rig;
pub mod subpixel;

use nalgebra::Point3;

pub use rig::{
    BASELINE_RANGE_M, FOCAL_RANGE, MAX_PIXEL_ASPECT, PRINCIPAL_POINT_MARGIN, RectifiedStereo,
};

use crate::features::{Descriptor, Features, GrayView, Keypoint};
use subpixel::{PairWindow, refine_disparity, refine_disparity_lk, row_offset};

/// Settings of [`match_stereo`].
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct StereoConfig {
    /// Largest row difference between a left and a right keypoint, pixels (default 1.0).
    pub row_tolerance_px: f32,
    /// Smallest disparity accepted, pixels (default 1.0).
    pub min_disparity_px: f32,
    /// Largest disparity searched, pixels (default 160).
    pub max_disparity_px: f32,
    /// Largest descriptor distance of a match (Hamming bits for binary descriptors,
    /// Euclidean for SURF) (default 50).
    pub max_distance: f32,
    /// Ratio test: best distance `<` ratio × second best (default 0.9).
    pub ratio: f32,
    /// Keep a match only when the right feature's best left candidate is the same
    /// feature (default true).
    pub left_right_check: bool,
    /// Half size of the block refining the disparity, pixels (`r` gives a `(2r+1)²`
    /// window); 0 keeps the keypoints' disparity (default 3).
    pub subpixel_radius: usize,
    /// After the parabola, refine the disparity by Gauss-Newton on the same window
    /// ([`subpixel::refine_disparity_lk`]) (default true).
    pub gauss_newton: bool,
    /// With `gauss_newton`, refine the disparity together with the vertical offset of the
    /// right window ([`subpixel::refine_disparity_lk_2d`]) rather than along the row alone
    /// (default true). A rectification that leaves the rows a fraction of a pixel apart
    /// (every real rig here: the rows' fit shows up to a pixel at the corners of KITTI's
    /// images) biases a disparity measured along the row by the row offset times the
    /// slant of the texture, and driving scenes are slanted towards the vanishing point in
    /// a pattern that shears the triangulated scene; measured in RESULTS.md.
    pub vertical_alignment: bool,
    /// Added to every measured disparity before triangulation, pixels (default 0): corrects a
    /// calibration whose right principal point is off.
    pub disparity_offset_px: f32,
    /// Points whose (corrected) disparity is below this are dropped, pixels (default 5,
    /// 80 m on KITTI's rig): their relative depth error `σ_d / d` is above 5 % at the
    /// default disparity noise, and a disparity bias of `b` px scales their depth by
    /// `b / d`. Keeping every point the matcher measures (1 px) was measured: more accurate
    /// on most figures (kitti_vo_seq2 aligned ATE 0.052 -> 0.045 m but drift 0.960 ->
    /// 0.967 %, Karlsruhe ATE 1.45 -> 1.36 %), and a quarter slower (RESULTS.md), which
    /// would leave the throughput bars no margin; so 5 px stays. A disparity, not a
    /// depth, so that which points are kept does not depend on the unit of the baseline
    /// or on the size of the scene (a rig calibrated in millimetres keeps the same points).
    pub min_point_disparity_px: f32,
    /// Assumed standard deviation of a disparity, pixels, for the per-point noise
    /// (default 0.25).
    pub disparity_sigma_px: f64,
    /// Assumed standard deviation of a keypoint position, pixels (default 0.5).
    pub position_sigma_px: f64,
    /// Measure the vertical offset between the images ([`StereoMatch::row_offset_px`],
    /// the evidence of a rectification error) of every `row_offset_stride`-th match; 0
    /// measures none (default 4: about a hundred a frame on KITTI, plenty for evidence
    /// summed over frames).
    pub row_offset_stride: usize,
}

impl StereoConfig {
    /// The default settings, usable in constants.
    pub const DEFAULT: Self = Self {
        row_tolerance_px: 1.0,
        min_disparity_px: 1.0,
        max_disparity_px: 160.0,
        max_distance: 50.0,
        ratio: 0.9,
        left_right_check: true,
        subpixel_radius: 3,
        gauss_newton: true,
        vertical_alignment: true,
        min_point_disparity_px: 5.0,
        disparity_offset_px: 0.0,
        disparity_sigma_px: 0.25,
        position_sigma_px: 0.5,
        row_offset_stride: 4,
    };
}

impl Default for StereoConfig {
    fn default() -> Self {
        Self::DEFAULT
    }
}

/// One stereo match and its triangulated point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StereoMatch {
    /// Index of the left feature.
    pub left: usize,
    /// Index of the right feature.
    pub right: usize,
    /// Sub-pixel disparity `u_left - u_right`, pixels.
    pub disparity_px: f32,
    /// The point, metres, in the left camera frame.
    pub point: Point3<f64>,
    /// Its noise level, metres: the root sum of squares of the depth and the lateral
    /// standard deviations ([`RectifiedStereo::point_sigma`]).
    pub sigma_m: f64,
    /// Its covariance, m² ([`RectifiedStereo::point_covariance`]).
    pub covariance: nalgebra::Matrix3<f64>,
    /// Row of the right feature minus row of the left one, pixels, measured on the
    /// images ([`subpixel::row_offset`]); 0 on a perfectly rectified pair, NaN when not
    /// measured.
    pub row_offset_px: f32,
}

/// Indices of `kps` sorted by row, with the rows and the columns in that order, for range
/// queries.
struct RowIndex {
    order: Vec<usize>,
    rows: Vec<f32>,
    columns: Vec<f32>,
}

impl RowIndex {
    fn new(kps: &[Keypoint]) -> Self {
        let mut order: Vec<usize> = (0..kps.len()).collect();
        // Ties by index: the order of a stable sort, without its buffer.
        order.sort_unstable_by(|&a, &b| kps[a].y.total_cmp(&kps[b].y).then(a.cmp(&b)));
        let rows = order.iter().map(|&i| kps[i].y).collect();
        let columns = order.iter().map(|&i| kps[i].x).collect();
        Self {
            order,
            rows,
            columns,
        }
    }

    /// Indices with a row in `[y - tol, y + tol]`, and their columns (none when the
    /// interval is empty: a negative or NaN `tol`).
    fn around(&self, y: f32, tol: f32) -> (&[usize], &[f32]) {
        let a = self.rows.partition_point(|&r| r < y - tol);
        let b = self.rows.partition_point(|&r| r <= y + tol).max(a);
        (&self.order[a..b], &self.columns[a..b])
    }
}

/// Best candidate of `query` among `cands` (indices into `descs`, with their columns)
/// allowed by `ok(candidate column)`: `(index, best, second best)` distances.
#[inline(always)]
fn best_two<D: Descriptor>(
    q: &D,
    (cands, columns): (&[usize], &[f32]),
    descs: &[D],
    mut ok: impl FnMut(f32) -> bool,
) -> Option<(usize, f32, f32)> {
    let mut best = (usize::MAX, f32::INFINITY, f32::INFINITY);
    for (&c, &x) in cands.iter().zip(columns) {
        if !ok(x) {
            continue;
        }
        let d = q.distance(&descs[c]);
        if d < best.1 {
            best = (c, d, best.1);
        } else if d < best.2 {
            best.2 = d;
        }
    }
    (best.0 != usize::MAX).then_some(best)
}

/// Matches left to right features of a rectified pair and triangulates the matches.
/// `left_img`/`right_img` are the images the features come from (for the sub-pixel
/// refinement). Matches are in ascending order of the left index. Compiled for the CPU's
/// best instruction set ([`crate::simd`]: the descriptor distances are population counts).
#[must_use]
pub fn match_stereo<D: Descriptor>(
    left: &Features<D>,
    right: &Features<D>,
    left_img: GrayView<'_>,
    right_img: GrayView<'_>,
    rig: &RectifiedStereo,
    config: &StereoConfig,
) -> Vec<StereoMatch> {
    crate::simd::dispatch(MatchStereo(
        [left, right],
        [left_img, right_img],
        rig,
        config,
    ))
}

/// A call of [`match_stereo`] for [`crate::simd::dispatch`].
struct MatchStereo<'a, D>(
    [&'a Features<D>; 2],
    [GrayView<'a>; 2],
    &'a RectifiedStereo,
    &'a StereoConfig,
);

impl<D: Descriptor> crate::simd::Kernel for MatchStereo<'_, D> {
    type Output = Vec<StereoMatch>;

    #[inline(always)]
    fn run(self) -> Vec<StereoMatch> {
        match_stereo_in(self.0, self.1, self.2, self.3)
    }
}

/// [`match_stereo`] on the (left, right) features and images, inlined into each
/// instruction set's compilation.
#[inline(always)]
fn match_stereo_in<D: Descriptor>(
    [left, right]: [&Features<D>; 2],
    [left_img, right_img]: [GrayView<'_>; 2],
    rig: &RectifiedStereo,
    config: &StereoConfig,
) -> Vec<StereoMatch> {
    let tol = config.row_tolerance_px;
    let (dmin, dmax) = (config.min_disparity_px, config.max_disparity_px);
    let right_rows = RowIndex::new(&right.keypoints);
    let left_rows = config
        .left_right_check
        .then(|| RowIndex::new(&left.keypoints));
    // At most one match per left feature.
    let mut out = Vec::with_capacity(left.len());
    for (li, lk) in left.keypoints.iter().enumerate() {
        let cands = right_rows.around(lk.y, tol);
        let Some((ri, d1, d2)) = best_two(&left.descriptors[li], cands, &right.descriptors, |x| {
            let d = lk.x - x;
            d >= dmin - 0.5 && d <= dmax
        }) else {
            continue;
        };
        if d1 > config.max_distance || d1 >= config.ratio * d2 {
            continue;
        }
        let rk = right.keypoints[ri];
        if let Some(lr) = &left_rows {
            let back = best_two(
                &right.descriptors[ri],
                lr.around(rk.y, tol),
                &left.descriptors,
                |x| {
                    let d = x - rk.x;
                    d >= dmin - 0.5 && d <= dmax
                },
            );
            if back.map(|b| b.0) != Some(li) {
                continue;
            }
        }
        let coarse = lk.x - rk.x;
        let disparity = if config.subpixel_radius > 0 {
            let (xl, y) = (
                lk.x.round().max(0.0) as usize,
                lk.y.round().max(0.0) as usize,
            );
            let window = PairWindow {
                left: left_img,
                right: right_img,
                xl,
                y,
                r: config.subpixel_radius,
            };
            let Some(d) = refine_disparity(window, i64::from(coarse.round() as i32), 2) else {
                continue;
            };
            // The disparity of the window at (xl, y) is that of the keypoint: a shift
            // within a constant-disparity window does not change it.
            let refined = match (config.gauss_newton, config.vertical_alignment) {
                (false, _) => Some(d),
                (true, true) => subpixel::refine_disparity_lk_2d(window, d, 8).map(|(d, _)| d),
                (true, false) => refine_disparity_lk(window, d, 8),
            };
            let Some(d) = refined else {
                continue;
            };
            d
        } else {
            coarse
        };
        let disparity = disparity + config.disparity_offset_px;
        if disparity < dmin || disparity > dmax {
            continue;
        }
        let Some(point) = rig.triangulate(f64::from(lk.x), f64::from(lk.y), f64::from(disparity))
        else {
            continue;
        };
        if disparity < config.min_point_disparity_px {
            continue;
        }
        let measure = config.row_offset_stride > 0 && out.len() % config.row_offset_stride == 0;
        let row_offset_px = if measure {
            let window = PairWindow {
                left: left_img,
                right: right_img,
                xl: lk.x.round().max(0.0) as usize,
                y: lk.y.round().max(0.0) as usize,
                r: config.subpixel_radius.max(2),
            };
            row_offset(window, disparity - config.disparity_offset_px).unwrap_or(f32::NAN)
        } else {
            f32::NAN
        };
        out.push(StereoMatch {
            row_offset_px,
            left: li,
            right: ri,
            disparity_px: disparity,
            point,
            sigma_m: rig.point_sigma(point.z, config.disparity_sigma_px, config.position_sigma_px),
            covariance: rig.point_covariance(
                f64::from(lk.x),
                f64::from(lk.y),
                f64::from(disparity),
                config.position_sigma_px,
                config.disparity_sigma_px,
            ),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::features::BinaryDescriptor;
    use crate::test_noise::Lcg;

    /// [`best_two`] as it was, over indices into the keypoints (their columns read there).
    fn best_two_by_index(
        q: &BinaryDescriptor,
        cands: &[usize],
        kps: &[Keypoint],
        descs: &[BinaryDescriptor],
        ok: impl Fn(f32) -> bool,
    ) -> Option<(usize, f32, f32)> {
        let mut best = (usize::MAX, f32::INFINITY, f32::INFINITY);
        for &c in cands {
            if !ok(kps[c].x) {
                continue;
            }
            let d = q.distance(&descs[c]);
            if d < best.1 {
                best = (c, d, best.1);
            } else if d < best.2 {
                best.2 = d;
            }
        }
        (best.0 != usize::MAX).then_some(best)
    }

    /// The row index's candidates with their columns give what the candidates with the
    /// keypoints' columns gave: the same best, distances and ties, on random keypoints
    /// (repeated rows and columns, few descriptor bits so that distances tie).
    #[test]
    fn best_two_with_columns_is_the_index_search() {
        let mut g = Lcg(36);
        let mut unit = move || (g.next_u32() >> 8) as f32 / (1u32 << 24) as f32;
        let kps: Vec<Keypoint> = (0..600)
            .map(|_| Keypoint {
                x: (unit() * 200.0 * 4.0).round() / 4.0,
                y: (unit() * 60.0 * 2.0).round() / 2.0,
                scale: 1.0,
                angle: 0.0,
                response: 1.0,
                octave: 0,
            })
            .collect();
        let descs: Vec<BinaryDescriptor> = (0..kps.len())
            .map(|_| BinaryDescriptor(std::array::from_fn(|_| u8::from(unit() < 0.1))))
            .collect();
        let index = RowIndex::new(&kps);
        let mut found = 0;
        for (q, k) in kps.iter().zip(&descs).take(300) {
            for tol in [0.0f32, 0.5, 1.0, 3.0] {
                let (cands, columns) = index.around(q.y, tol);
                assert_eq!(cands.len(), columns.len());
                let ok = |x: f32| {
                    let d = q.x - x;
                    (0.5..=60.0).contains(&d)
                };
                let got = best_two(k, (cands, columns), &descs, ok);
                assert_eq!(
                    got.map(|(i, a, b)| (i, a.to_bits(), b.to_bits())),
                    best_two_by_index(k, cands, &kps, &descs, ok).map(|(i, a, b)| (
                        i,
                        a.to_bits(),
                        b.to_bits()
                    )),
                    "({}, {}), tol {tol}",
                    q.x,
                    q.y
                );
                found += usize::from(got.is_some());
            }
        }
        assert!(found > 300, "{found}");
    }

    #[test]
    fn a_negative_or_nan_row_tolerance_finds_no_candidate() {
        let kps: Vec<Keypoint> = (0..50)
            .map(|i| Keypoint {
                x: i as f32,
                y: (i % 7) as f32,
                scale: 3.0,
                angle: 0.0,
                response: 1.0,
                octave: 0,
            })
            .collect();
        let index = RowIndex::new(&kps);
        assert_eq!(index.around(3.0, 0.0).0.len(), 7);
        for tol in [-1.0f32, -0.25, f32::NAN] {
            let (cands, columns) = index.around(3.0, tol);
            assert!(cands.is_empty() && columns.is_empty(), "tol {tol}");
        }
    }

    #[test]
    fn triangulation_formula() {
        let rig = RectifiedStereo {
            fx: 500.0,
            fy: 500.0,
            cx: 320.0,
            cy: 240.0,
            baseline_m: 0.5,
        };
        let p = rig.triangulate(420.0, 140.0, 25.0).expect("positive");
        assert!((p.z - 10.0).abs() < 1e-12);
        assert!((p.x - 2.0).abs() < 1e-12 && (p.y + 2.0).abs() < 1e-12);
        assert!(rig.triangulate(1.0, 1.0, 0.0).is_none());
        let (u, v) = rig.project_left(&p);
        assert!((u - 420.0).abs() < 1e-9 && (v - 140.0).abs() < 1e-9);
    }
}
