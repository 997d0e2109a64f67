//! Arun, Huang & Blostein (1987): least-squares rigid motion between matched point sets,
//! eq. (6)-(8), with the reflection guard and optional per-point weights.
//!
//! With weights `w_i >= 0` and weighted centroids `s̄ = Σ w s / Σ w`, `d̄ = Σ w d / Σ w`,
//!
//! ```text
//! H = Σ w_i (s_i - s̄)(d_i - d̄)^T = U Σ V^T,
//! R = V diag(1, 1, det(V U^T)) U^T,      t = d̄ - R s̄,
//! ```
//!
//! minimises `Σ w_i |d_i - (R s_i + t)|^2` over proper rotations: the `det` term flips the
//! axis of the smallest singular value when the unconstrained optimum is a reflection
//! (planar or noisy sets), so `det R = +1` always.

mod mirror;

pub use mirror::{MIRROR_RATIO, Mirror, mirror_image};

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};

use crate::error::{DegeneracyKind, PoseError};
use crate::geometry::check_spread;

/// Iteration cap of the 3x3 decompositions (they converge in a handful).
pub(crate) const MAX_DECOMPOSITION_ITERATIONS: usize = 200;

/// Relative size of the second singular value of `H` below which it counts as rank 1.
const RANK_TOLERANCE: f64 = 1e-12;

/// Least-squares rigid motion `dst ≈ R src + t` over all pairs (equal weights).
///
/// # Errors
/// [`PoseError::LengthMismatch`], [`PoseError::TooFewPoints`] (below 3 points),
/// [`PoseError::Degenerate`] for coincident or collinear sets.
pub fn arun(src: &[Point3<f64>], dst: &[Point3<f64>]) -> Result<Isometry3<f64>, PoseError> {
    arun_weighted(src, dst, None)
}

/// Weighted least-squares rigid motion; `weights[i] >= 0` scales pair `i`'s squared
/// residual (for example `1 / σ_i^2` for a per-point noise level σ_i in metres).
///
/// # Errors
/// As [`arun`], plus [`PoseError::InvalidConfig`] for a negative, non-finite or
/// wrongly sized weight vector.
pub fn arun_weighted(
    src: &[Point3<f64>],
    dst: &[Point3<f64>],
    weights: Option<&[f64]>,
) -> Result<Isometry3<f64>, PoseError> {
    if src.len() != dst.len() {
        return Err(PoseError::LengthMismatch {
            src: src.len(),
            dst: dst.len(),
        });
    }
    if let Some(w) = weights {
        if w.len() != src.len() {
            return Err(PoseError::InvalidConfig(format!(
                "{} weights for {} points",
                w.len(),
                src.len()
            )));
        }
        if w.iter().any(|v| !v.is_finite() || *v < 0.0) {
            return Err(PoseError::InvalidConfig(
                "weights must be finite and non-negative".into(),
            ));
        }
    }
    if src.len() < 3 {
        return Err(PoseError::TooFewPoints {
            got: src.len(),
            needed: 3,
        });
    }
    check_spread(src, "source")?;
    check_spread(dst, "destination")?;
    let pairs = (0..src.len()).map(|i| (&src[i], &dst[i], weights.map_or(1.0, |w| w[i])));
    arun_pairs(pairs)
}

/// Arun on an iterator of `(src, dst, weight)` triples, walked twice. No allocation: the
/// hot loops of the estimators call this on index subsets.
///
/// Checks only that the weights do not vanish and that `H` has rank >= 2; callers check
/// the spread of the sets when they need a named error.
///
/// # Errors
/// [`PoseError::Degenerate`] with [`DegeneracyKind::RankDeficient`].
pub fn arun_pairs<'a, I>(pairs: I) -> Result<Isometry3<f64>, PoseError>
where
    I: Iterator<Item = (&'a Point3<f64>, &'a Point3<f64>, f64)> + Clone,
{
    let mut wsum = 0.0;
    let mut cs = Vector3::zeros();
    let mut cd = Vector3::zeros();
    for (s, d, w) in pairs.clone() {
        wsum += w;
        cs += s.coords * w;
        cd += d.coords * w;
    }
    let rank_error = PoseError::Degenerate {
        set: "inlier",
        kind: DegeneracyKind::RankDeficient,
    };
    if wsum <= 0.0 || !wsum.is_finite() {
        return Err(rank_error);
    }
    cs /= wsum;
    cd /= wsum;
    let mut h = Matrix3::zeros();
    for (s, d, w) in pairs {
        h += (s.coords - cs) * ((d.coords - cd) * w).transpose();
    }
    let rotation = rotation_from_cross_covariance(&h).ok_or(rank_error)?;
    let t = cd - rotation * cs;
    Ok(Isometry3::from_parts(Translation3::from(t), rotation))
}

/// The proper rotation `R` minimising
/// `Σ |d_c - R s_c|^2` for `H = Σ s_c d_c^T`; `None` when `H` has rank below 2 or is not
/// finite.
#[must_use]
pub fn rotation_from_cross_covariance(h: &Matrix3<f64>) -> Option<UnitQuaternion<f64>> {
    if !h.iter().all(|v| v.is_finite()) {
        return None;
    }
    // Capped iterations: nalgebra's plain `svd` has no cap and can spin on pathological
    // input. Singular values come sorted descending.
    let svd = h.try_svd(true, true, f64::EPSILON, MAX_DECOMPOSITION_ITERATIONS)?;
    let (u, v_t) = (svd.u?, svd.v_t?);
    let sv = svd.singular_values;
    if sv[0] <= 0.0 || sv[1] <= RANK_TOLERANCE * sv[0] {
        return None;
    }
    let v = v_t.transpose();
    let d = (v * u.transpose()).determinant().signum();
    let r = v * Matrix3::from_diagonal(&Vector3::new(1.0, 1.0, d)) * u.transpose();
    // Through the quaternion: orthonormal to machine precision, det = +1.
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    Some(UnitQuaternion::new_normalize(q.into_inner()))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn cloud() -> Vec<Point3<f64>> {
        (0..12)
            .map(|i| {
                let f = i as f64;
                Point3::new(
                    (f * 1.3).sin() * 4.0,
                    (f * 0.7).cos() * 3.0,
                    5.0 + (f * 2.1).sin(),
                )
            })
            .collect()
    }

    #[test]
    fn exact_on_noise_free_data() {
        let truth = Isometry3::new(Vector3::new(0.4, -1.0, 2.0), Vector3::new(0.3, -0.2, 0.9));
        let src = cloud();
        let dst: Vec<_> = src.iter().map(|p| truth * p).collect();
        let est = arun(&src, &dst).expect("solvable");
        assert!((est.to_homogeneous() - truth.to_homogeneous()).norm() < 1e-12);
    }

    #[test]
    fn planar_set_gives_rotation_not_reflection() {
        let truth = Isometry3::new(Vector3::new(0.0, 0.0, 1.0), Vector3::new(0.0, 2.0, 0.0));
        let src: Vec<_> = (0..9)
            .map(|i| Point3::new((i % 3) as f64, (i / 3) as f64, 0.0))
            .collect();
        let dst: Vec<_> = src.iter().map(|p| truth * p).collect();
        let est = arun(&src, &dst).expect("solvable");
        let r = est.rotation.to_rotation_matrix().into_inner();
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        assert!((est.to_homogeneous() - truth.to_homogeneous()).norm() < 1e-12);
    }

    #[test]
    fn reflected_data_still_gives_proper_rotation() {
        // dst is a mirror image of src: the best proper rotation, never det = -1.
        let src = cloud();
        let dst: Vec<_> = src.iter().map(|p| Point3::new(-p.x, p.y, p.z)).collect();
        let est = arun(&src, &dst).expect("solvable");
        let r = est.rotation.to_rotation_matrix().into_inner();
        assert!((r.determinant() - 1.0).abs() < 1e-12);
    }

    #[test]
    fn weights_select_points() {
        let truth = Isometry3::new(Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.2));
        let src = cloud();
        let mut dst: Vec<_> = src.iter().map(|p| truth * p).collect();
        dst[0] = Point3::new(100.0, 100.0, 100.0);
        let mut w = vec![1.0; src.len()];
        w[0] = 0.0;
        let est = arun_weighted(&src, &dst, Some(&w)).expect("solvable");
        assert!((est.to_homogeneous() - truth.to_homogeneous()).norm() < 1e-12);
    }

    #[test]
    fn degenerate_inputs_are_errors() {
        let p = Point3::new(1.0, 1.0, 1.0);
        assert!(matches!(
            arun(&[p, p], &[p, p]),
            Err(PoseError::TooFewPoints { got: 2, needed: 3 })
        ));
        assert!(matches!(
            arun(&[p; 5], &[p; 5]),
            Err(PoseError::Degenerate {
                kind: DegeneracyKind::Coincident,
                ..
            })
        ));
        let line: Vec<_> = (0..5).map(|i| Point3::new(i as f64, 0.0, 0.0)).collect();
        assert!(matches!(
            arun(&line, &line),
            Err(PoseError::Degenerate {
                kind: DegeneracyKind::Collinear,
                ..
            })
        ));
        let w = [1.0, -1.0, 1.0];
        let tri = cloud()[..3].to_vec();
        assert!(matches!(
            arun_weighted(&tri, &tri, Some(&w)),
            Err(PoseError::InvalidConfig(_))
        ));
    }
}
