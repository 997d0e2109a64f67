//! Is a point set a mirror image of another? A reflection is not a rotation: the best
//! rotation then leaves residuals far above any inlier threshold, and an estimator that
//! reports it would answer with a motion that explains nothing.

use nalgebra::{Matrix3, Point3, Vector3};

use super::MAX_DECOMPOSITION_ITERATIONS;

/// How much better a reflection fits than the best rotation to make a set a mirror image:
/// the reflection's residual RMS at most a third of the rotation's.
pub const MIRROR_RATIO: f64 = 3.0;

/// The two best orthogonal fits of `dst` from `src` (all points, centred), when the
/// reflection fits at least [`MIRROR_RATIO`] times better (RMS) than any rotation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mirror {
    /// Residual RMS of the best rotation and translation, in the points' unit.
    pub rms_rotation: f64,
    /// Residual RMS of the best reflection and translation, in the points' unit.
    pub rms_reflection: f64,
}

/// [`Mirror`] when `dst` is a mirror image of `src` (same length, at least 3 points),
/// else `None`. From the singular values `σ` of the cross-covariance `H`: the sums of
/// squares are `A - 2(σ1 + σ2 ± σ3)`, the sign of `det H` telling which is the rotation.
#[must_use]
pub fn mirror_image(src: &[Point3<f64>], dst: &[Point3<f64>]) -> Option<Mirror> {
    let n = src.len();
    if n < 3 || dst.len() != n {
        return None;
    }
    let mean = |p: &[Point3<f64>]| p.iter().map(|q| q.coords).sum::<Vector3<f64>>() / n as f64;
    let (cs, cd) = (mean(src), mean(dst));
    let mut h = Matrix3::zeros();
    let mut a = 0.0;
    for (s, d) in src.iter().zip(dst) {
        let (s, d) = (s.coords - cs, d.coords - cd);
        h += s * d.transpose();
        a += s.norm_squared() + d.norm_squared();
    }
    if !(a.is_finite() && h.iter().all(|v| v.is_finite())) {
        return None;
    }
    let sv = h
        .try_svd(false, false, f64::EPSILON, MAX_DECOMPOSITION_ITERATIONS)?
        .singular_values;
    let sign = h.determinant().signum();
    let common = sv[0] + sv[1];
    let rms = |ss: f64| (ss.max(0.0) / n as f64).sqrt();
    let rms_rotation = rms(a - 2.0 * (common + sign * sv[2]));
    let rms_reflection = rms(a - 2.0 * (common - sign * sv[2]));
    (rms_rotation > MIRROR_RATIO * rms_reflection).then_some(Mirror {
        rms_rotation,
        rms_reflection,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Isometry3, Vector3};

    fn cloud() -> Vec<Point3<f64>> {
        (0..12)
            .map(|i| {
                let f = f64::from(i);
                Point3::new(f * 0.7 - 2.0, (f * 1.3).sin() * 3.0, 4.0 + (f * 0.9).cos())
            })
            .collect()
    }

    #[test]
    fn mirrored_sets_are_told_from_rotated_ones() {
        let src = cloud();
        let mirrored: Vec<_> = src.iter().map(|p| Point3::from(-p.coords)).collect();
        let m = mirror_image(&src, &mirrored).expect("a mirror image");
        assert!(m.rms_reflection < 1e-6 && m.rms_rotation > 0.5, "{m:?}");
        let flipped: Vec<_> = src.iter().map(|p| Point3::new(p.x, p.y, -p.z)).collect();
        assert!(mirror_image(&src, &flipped).is_some());
        let motion = Isometry3::new(Vector3::new(1.0, -2.0, 0.5), Vector3::new(0.3, -0.2, 1.1));
        let moved: Vec<_> = src.iter().map(|p| motion * p).collect();
        assert_eq!(mirror_image(&src, &moved), None);
        // A flat set: its mirror image through its own plane is also a rotation.
        let plane: Vec<_> = src.iter().map(|p| Point3::new(p.x, p.y, 1.0)).collect();
        let plane_flipped: Vec<_> = plane.iter().map(|p| Point3::new(-p.x, p.y, 1.0)).collect();
        assert_eq!(mirror_image(&plane, &plane_flipped), None);
    }
}
