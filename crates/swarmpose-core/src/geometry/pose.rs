//! Rigid transforms (eq. 1-2), quaternion conventions and rotation errors (eq. 20).

use nalgebra::{Isometry3, Matrix3, UnitQuaternion, Vector3};

/// The quaternion of a rotation as `[w, x, y, z]`, canonical among `q` and `-q` (one
/// rotation): `w >= 0`, and for `w = 0` (half turns) the first non-zero of `x, y, z` is
/// positive. Negative zeros come out as `+0.0`.
#[must_use]
pub fn quaternion_wxyz(q: &UnitQuaternion<f64>) -> [f64; 4] {
    let c = q.quaternion().coords; // nalgebra stores [x, y, z, w]
    let lead = [c.w, c.x, c.y, c.z]
        .into_iter()
        .find(|v| *v != 0.0)
        .unwrap_or(1.0);
    let s = if lead < 0.0 { -1.0 } else { 1.0 };
    // `+ 0.0` turns -0.0 into +0.0.
    [s * c.w + 0.0, s * c.x + 0.0, s * c.y + 0.0, s * c.z + 0.0]
}

/// Angle (radians, in `[0, π]`) of the rotation that takes `a` to `b`.
#[must_use]
pub fn rotation_angle_between(a: &UnitQuaternion<f64>, b: &UnitQuaternion<f64>) -> f64 {
    a.angle_to(b)
}

/// The paper's rotation error, eq. (20): `||I - R_ref R^T||_F` (dimensionless; equals
/// `2 sqrt(2) |sin(θ/2)|` for a residual rotation of angle `θ`).
#[must_use]
pub fn frobenius_rotation_error(r_ref: &UnitQuaternion<f64>, r: &UnitQuaternion<f64>) -> f64 {
    let m =
        r_ref.to_rotation_matrix().into_inner() * r.to_rotation_matrix().into_inner().transpose();
    (Matrix3::identity() - m).norm()
}

/// Chains relative motions into absolute poses, eq. (2): `C_m = C_{m-1} T_m`, starting
/// from `C_0 = start`. Returns `C_0, C_1, ..., C_n` (one more pose than motions).
#[must_use]
pub fn chain<'a, I>(start: Isometry3<f64>, motions: I) -> Vec<Isometry3<f64>>
where
    I: IntoIterator<Item = &'a Isometry3<f64>>,
{
    let mut poses = vec![start];
    let mut current = start;
    for t in motions {
        current *= t;
        poses.push(current);
    }
    poses
}

/// Rotates `v` by angle `theta` (radians) about the unit axis `k` with the Rodrigues
/// form of eq. (14): `cos θ v + sin θ k × v + (1 - cos θ) k (k · v)`.
#[must_use]
pub fn rodrigues_rotate(k: &Vector3<f64>, theta: f64, v: &Vector3<f64>) -> Vector3<f64> {
    v * theta.cos() + k.cross(v) * theta.sin() + k * (k.dot(v) * (1.0 - theta.cos()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Eq. (12) with its sign typos corrected: the matrix of `q = [q0, q1, q2, q3]`.
    fn eq12_corrected(q: [f64; 4]) -> Matrix3<f64> {
        let [q0, q1, q2, q3] = q;
        Matrix3::new(
            q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3,
            2.0 * (q1 * q2 - q3 * q0),
            2.0 * (q1 * q3 + q2 * q0),
            2.0 * (q1 * q2 + q3 * q0),
            q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3,
            2.0 * (q2 * q3 - q1 * q0),
            2.0 * (q1 * q3 - q2 * q0),
            2.0 * (q2 * q3 + q1 * q0),
            q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3,
        )
    }

    /// Eq. (12) exactly as printed in the paper.
    fn eq12_as_printed(q: [f64; 4]) -> Matrix3<f64> {
        let [q0, q1, q2, q3] = q;
        Matrix3::new(
            q0 * q0 + q1 * q1 - q2 * q2 - q3 * q3,
            2.0 * (q1 * q2 + q3 * q0),
            2.0 * (q1 * q3 - q2 * q0),
            2.0 * (q1 * q2 + q3 * q0),
            q0 * q0 - q1 * q1 + q2 * q2 - q3 * q3,
            2.0 * (q1 * q3 + q2 * q0),
            2.0 * (q1 * q3 - q2 * q0),
            2.0 * (q1 * q3 + q2 * q0),
            q0 * q0 - q1 * q1 - q2 * q2 + q3 * q3,
        )
    }

    #[test]
    fn quaternion_rotation_equals_rodrigues_eq14() {
        let axis = Vector3::new(0.2, -0.5, 0.8).normalize();
        for &theta in &[0.0, 0.1, 1.0, 2.5, std::f64::consts::PI - 1e-3] {
            let q = UnitQuaternion::from_axis_angle(&nalgebra::Unit::new_unchecked(axis), theta);
            let v = Vector3::new(1.5, -2.0, 7.0);
            // q v q^-1 (nalgebra's quaternion sandwich) equals eq. (14).
            let sandwich = q * v;
            let rod = rodrigues_rotate(&axis, theta, &v);
            assert!((sandwich - rod).norm() < 1e-12, "theta {theta}");
            // nalgebra's matrix equals eq. (12) corrected.
            let m = q.to_rotation_matrix().into_inner();
            assert!((m - eq12_corrected(quaternion_wxyz(&q))).norm() < 1e-12);
        }
    }

    #[test]
    fn eq12_as_printed_is_not_a_rotation() {
        let q = UnitQuaternion::from_euler_angles(0.3, -0.2, 0.9);
        let m = eq12_as_printed(quaternion_wxyz(&q));
        // Symmetric off-diagonal terms: not orthonormal for a generic rotation.
        assert!((m * m.transpose() - Matrix3::identity()).norm() > 0.1);
    }

    #[test]
    fn wxyz_is_canonical_for_half_turns() {
        let half = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), std::f64::consts::PI);
        let neg = UnitQuaternion::new_unchecked(-half.into_inner());
        let (a, b) = (quaternion_wxyz(&half), quaternion_wxyz(&neg));
        assert!(
            a.iter().zip(&b).all(|(x, y)| (x - y).abs() < 1e-15),
            "{a:?} vs {b:?}"
        );
        assert!(a[2] > 0.0 && a[0].abs() < 1e-15);
        let exact = UnitQuaternion::new_unchecked(nalgebra::Quaternion::new(-0.0, 0.0, -1.0, 0.0));
        let w = quaternion_wxyz(&exact);
        assert_eq!(w, [0.0, 0.0, 1.0, 0.0]);
        assert!(w[0].is_sign_positive());
    }

    #[test]
    fn wxyz_has_nonnegative_w() {
        let q = UnitQuaternion::from_euler_angles(3.0, 0.0, 0.0);
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        assert_eq!(quaternion_wxyz(&q), quaternion_wxyz(&neg));
        assert!(quaternion_wxyz(&neg)[0] >= 0.0);
    }

    #[test]
    fn eq20_matches_angle() {
        let a = UnitQuaternion::from_euler_angles(0.1, 0.2, 0.3);
        let delta = UnitQuaternion::from_euler_angles(0.0, 0.0, 0.05);
        let b = delta * a;
        let theta = rotation_angle_between(&a, &b);
        assert!((theta - 0.05).abs() < 1e-12);
        let f = frobenius_rotation_error(&b, &a);
        assert!((f - 2.0 * 2f64.sqrt() * (theta / 2.0).sin()).abs() < 1e-12);
        assert!(frobenius_rotation_error(&a, &a) < 1e-15);
    }

    #[test]
    fn chain_composes_eq2() {
        let t1 = Isometry3::new(Vector3::new(1.0, 0.0, 0.0), Vector3::new(0.0, 0.0, 0.5));
        let t2 = Isometry3::new(Vector3::new(0.0, 2.0, 0.0), Vector3::new(0.1, 0.0, 0.0));
        let poses = chain(Isometry3::identity(), [&t1, &t2]);
        assert_eq!(poses.len(), 3);
        let expect = t1 * t2;
        assert!((poses[2].to_homogeneous() - expect.to_homogeneous()).norm() < 1e-15);
    }
}
