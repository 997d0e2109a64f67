//! The map from a particle's position in R^3 to a unit quaternion.
//!
//! A particle is the rotation vector `x = θ k` (axis `k`, angle `θ` in radians), and
//!
//! ```text
//! q(x) = [cos(|x|/2), sin(|x|/2) x/|x|]        (eq. 10),   q(0) = [1, 0, 0, 0].
//! ```
//!
//! This is the exponential map of SO(3). Properties the estimators rely on:
//! - `|q(x)| = 1` for every `x`, so every particle is a valid rotation (eq. 11);
//! - every rotation is reached inside the closed ball `|x| <= π`, hence inside the
//!   search box `[-π, π]^3`; points outside the ball are valid rotations too
//!   (`x` and `x (1 - 2π/|x|)` give the same rotation), so clamping is never needed
//!   for validity;
//! - `q` and `-q` are one rotation: [`particle_from_rotation`] picks `w >= 0`, so the
//!   returned vector has `|x| <= π`;
//! - near `x = 0` the map is smooth and `q ≈ [1, x/2]`, so small moves of a particle are
//!   small rotations.

use nalgebra::{UnitQuaternion, Vector3};

/// The unit quaternion of rotation vector `x` (radians).
#[inline]
#[must_use]
pub fn rotation_from_particle(x: &[f64; 3]) -> UnitQuaternion<f64> {
    UnitQuaternion::from_scaled_axis(Vector3::new(x[0], x[1], x[2]))
}

/// Maps a rotation vector to the equivalent one in the ball `|x| <= π` (same rotation):
/// `x (1 - 2π/|x|)` while `|x| > π`. With it the search space of a swarm over rotation
/// vectors has no boundary: a particle leaving the ball re-enters on the other side.
#[inline]
pub fn wrap_rotation_vector(x: &mut [f64; 3]) {
    use std::f64::consts::PI;
    let mut n = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
    while n > PI && n.is_finite() {
        let f = 1.0 - 2.0 * PI / n;
        for v in x.iter_mut() {
            *v *= f;
        }
        n = (n - 2.0 * PI).abs();
    }
}

/// The rotation vector (radians, `|x| <= π`) of a unit quaternion; inverse of
/// [`rotation_from_particle`] on that ball.
#[must_use]
pub fn particle_from_rotation(q: &UnitQuaternion<f64>) -> [f64; 3] {
    let v = q.scaled_axis();
    [v.x, v.y, v.z]
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    #[test]
    fn round_trip_and_antipodes() {
        let x = [0.3, -1.1, 0.7];
        let q = rotation_from_particle(&x);
        assert!((q.norm() - 1.0).abs() < 1e-15);
        let back = particle_from_rotation(&q);
        for k in 0..3 {
            assert!((back[k] - x[k]).abs() < 1e-12);
        }
        // Beyond the ball: same rotation as the wrapped vector.
        let n = (x[0] * x[0] + x[1] * x[1] + x[2] * x[2]).sqrt();
        let f = 1.0 - 2.0 * PI / n;
        let wrapped = rotation_from_particle(&[x[0] * f, x[1] * f, x[2] * f]);
        assert!(q.angle_to(&wrapped) < 1e-12);
        // q and -q: one rotation.
        let neg = UnitQuaternion::new_unchecked(-q.into_inner());
        assert!(
            q.to_rotation_matrix().matrix() == neg.to_rotation_matrix().matrix() || {
                (q.to_rotation_matrix().matrix() - neg.to_rotation_matrix().matrix()).norm() < 1e-15
            }
        );
    }

    #[test]
    fn wrapping_keeps_the_rotation() {
        for x in [
            [4.0, 0.0, 0.0],
            [3.0, 3.0, 3.0],
            [-7.0, 1.0, 0.5],
            [0.1, 0.2, 0.3],
        ] {
            let mut w = x;
            wrap_rotation_vector(&mut w);
            let n = (w[0] * w[0] + w[1] * w[1] + w[2] * w[2]).sqrt();
            assert!(n <= PI + 1e-12, "{w:?}");
            assert!(rotation_from_particle(&x).angle_to(&rotation_from_particle(&w)) < 1e-12);
        }
    }

    #[test]
    fn identity_at_origin() {
        let q = rotation_from_particle(&[0.0; 3]);
        assert_eq!(q, UnitQuaternion::identity());
    }
}
