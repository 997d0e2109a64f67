//! The pose parameterisation shared by the solvers: a rigid transform `T` as a rotation
//! matrix and a translation (`P ↦ R P + t`, metres), perturbed on the left as
//! `T ← E(ξ) T` with `E(ξ): P ↦ Exp(ω) P + ν`, `ξ = (ν, ω)` (metres, radians, in the
//! frame `T` maps into).

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};

/// A rigid transform as a rotation matrix and translation (`P ↦ rot P + trans`, metres).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Pose {
    pub(crate) rot: Matrix3<f64>,
    pub(crate) trans: Vector3<f64>,
}

impl Pose {
    /// The transform of an isometry.
    pub(crate) fn of(t: &Isometry3<f64>) -> Self {
        Self {
            rot: *t.rotation.to_rotation_matrix().matrix(),
            trans: t.translation.vector,
        }
    }

    /// `E(ξ) T`: `P ↦ Exp(ω) (R P + t) + ν`, `ξ = (ν, ω)`.
    pub(crate) fn moved(&self, nu: &Vector3<f64>, omega: &Vector3<f64>) -> Self {
        let e = *UnitQuaternion::from_scaled_axis(*omega)
            .to_rotation_matrix()
            .matrix();
        Self {
            rot: e * self.rot,
            trans: e * self.trans + nu,
        }
    }

    /// The transform as an isometry (its rotation through [`unit_quaternion`]).
    pub(crate) fn isometry(&self) -> Isometry3<f64> {
        Isometry3::from_parts(Translation3::from(self.trans), unit_quaternion(&self.rot))
    }

    /// `T_ja = T_jw T_aw⁻¹` for `self = T_jw`, `a = T_aw`.
    pub(crate) fn relative_to(&self, a: &Self) -> (Matrix3<f64>, Vector3<f64>) {
        let rot = self.rot * a.rot.transpose();
        (rot, self.trans - rot * a.trans)
    }
}

/// The unit quaternion of a rotation matrix, for any angle (nalgebra's iterative
/// `from_matrix` starts from the identity and is inaccurate far from it), normalised
/// against rounding.
pub(crate) fn unit_quaternion(rot: &Matrix3<f64>) -> UnitQuaternion<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*rot));
    UnitQuaternion::new_normalize(q.into_inner())
}
