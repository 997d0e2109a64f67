//! Step 3 of `pso`: the translation, voted by the points once the rotation is known.

use nalgebra::{Matrix3, Vector3};

use crate::estimators::consensus::Tolerance;
use crate::geometry::Correspondences;

/// Number of anchor points whose translation proposals are voted on.
pub(super) const ANCHORS: usize = 32;

/// The translation with the most agreeing proposals `t_i = d_i - R s_i`: each anchor's
/// proposal `t_c` counts the points with `|t_i - t_c| < δ_i + δ_c`; the best anchor wins
/// and its agreeing proposals are averaged (weighted by `1 / δ_i²`). `None` without
/// anchors.
pub(super) fn translation(
    data: &Correspondences,
    rotation: &Matrix3<f64>,
    anchors: &[usize],
    tol: Tolerance<'_>,
) -> Option<Vector3<f64>> {
    let proposals: Vec<Vector3<f64>> = data
        .src()
        .iter()
        .zip(data.dst())
        .map(|(s, d)| d.coords - rotation * s.coords)
        .collect();
    let agrees = |c: usize, i: usize| {
        (proposals[i] - proposals[c]).norm_squared() < (tol.at(i) + tol.at(c)).powi(2)
    };
    let mut best: Option<(usize, usize)> = None;
    for &c in anchors {
        let count = (0..proposals.len()).filter(|&i| agrees(c, i)).count();
        if best.is_none_or(|(b, _)| count > b) {
            best = Some((count, c));
        }
    }
    let (_, c) = best?;
    let (sum, k) = (0..proposals.len())
        .filter(|&i| agrees(c, i))
        .fold((Vector3::zeros(), 0usize), |(s, k), i| {
            (s + proposals[i], k + 1)
        });
    Some(sum / k as f64)
}
