//! Checks and closed-form spectra of 3 × 3 covariance matrices (m²).

use nalgebra::Matrix3;

/// Checks a noise covariance (m²): `Ok` when `c` is finite, symmetric (to a relative 1e-9)
/// and positive definite (Sylvester's criterion).
///
/// # Errors
/// Why it is not: `"is not finite"`, `"is not symmetric"` or
/// `"is not positive definite"`.
pub fn check_covariance(c: &Matrix3<f64>) -> Result<(), &'static str> {
    if !c.iter().all(|v| v.is_finite()) {
        return Err("is not finite");
    }
    let scale = c.abs().max().max(f64::MIN_POSITIVE);
    if (c - c.transpose()).abs().max() > 1e-9 * scale {
        return Err("is not symmetric");
    }
    // Sylvester's criterion: all leading principal minors positive.
    let m1 = c[(0, 0)];
    let m2 = c[(0, 0)] * c[(1, 1)] - c[(0, 1)] * c[(1, 0)];
    let m3 = c.determinant();
    if m1 > 0.0 && m2 > 0.0 && m3 > 0.0 {
        Ok(())
    } else {
        Err("is not positive definite")
    }
}

/// Largest eigenvalue of a symmetric 3 × 3 matrix, by the closed trigonometric form of
/// the characteristic cubic (no iteration).
#[must_use]
pub(crate) fn largest_eigenvalue(c: &Matrix3<f64>) -> f64 {
    let p1 = c[(0, 1)].powi(2) + c[(0, 2)].powi(2) + c[(1, 2)].powi(2);
    let q = c.trace() / 3.0;
    if p1 == 0.0 {
        return c[(0, 0)].max(c[(1, 1)]).max(c[(2, 2)]);
    }
    let p2 = (c[(0, 0)] - q).powi(2) + (c[(1, 1)] - q).powi(2) + (c[(2, 2)] - q).powi(2) + 2.0 * p1;
    let p = (p2 / 6.0).sqrt();
    let b = (c - Matrix3::identity() * q) / p;
    let r = (b.determinant() / 2.0).clamp(-1.0, 1.0);
    let phi = r.acos() / 3.0;
    q + 2.0 * p * phi.cos()
}

#[cfg(test)]
mod tests {
    use nalgebra::{Rotation3, Vector3};

    use super::*;

    #[test]
    fn largest_eigenvalue_of_a_rotated_diagonal() {
        for (k, axis) in [Vector3::x(), Vector3::new(0.3, -1.0, 0.5), Vector3::z()]
            .iter()
            .enumerate()
        {
            let r =
                Rotation3::from_axis_angle(&nalgebra::Unit::new_normalize(*axis), 0.4 + k as f64);
            let d = Matrix3::from_diagonal(&Vector3::new(0.5, 3.0, 1.25));
            let c = r.matrix() * d * r.matrix().transpose();
            assert!((largest_eigenvalue(&c) - 3.0).abs() < 1e-12);
            assert!(check_covariance(&c).is_ok());
        }
        assert_eq!(largest_eigenvalue(&Matrix3::identity()), 1.0);
    }

    #[test]
    fn rejects_bad_matrices() {
        let mut c = Matrix3::identity();
        c[(2, 2)] = f64::NAN;
        assert_eq!(check_covariance(&c), Err("is not finite"));
        assert_eq!(
            check_covariance(&-Matrix3::identity()),
            Err("is not positive definite")
        );
        assert_eq!(
            check_covariance(&Matrix3::zeros()),
            Err("is not positive definite")
        );
    }
}
