//! The measurement model of [`super::model`] with its constants computed once per
//! refinement, not once per point (issue 34): `f b` and the whitening `1/σ`, and the
//! disparity correction `δ` evaluated inline (`DisparityCorrection::at_normalised` is
//! not inlined across crates, a call per point and measurement). Every function here
//! is the [`StereoModel`] method of the same name with the same floating-point
//! operations in the same order, the same bits (the tests compare them).

use nalgebra::{Matrix3, Vector3};
use swarmpose_vision::frontend::DisparityCorrection;

use super::model::FOCAL_TERM;
use super::model::{Linearized, Matrix3x6, Matrix3xK, Parts, StereoModel, StereoObservation};

/// A [`StereoModel`] with the values that depend on it alone computed once.
#[derive(Debug, Clone, Copy)]
pub(crate) struct Prepared {
    /// The model.
    pub(crate) model: StereoModel,
    /// `fx b`, pixels metres.
    fb: f64,
    /// The whitening `(1/σ_p, 1/σ_p, 1/σ_d)`.
    w: Vector3<f64>,
    /// The whitening as a diagonal matrix, opaque to the optimiser: with its zeros
    /// known at compile time, LLVM compiled the products with it and `∂pred/∂h` with an
    /// AVX register move (`vmovq xmm, xmm` in its `66 0F D6` form) that valgrind 3.19
    /// cannot decode, which stops cachegrind's counts of the whole run. The same bits:
    /// the multiplications by its zeros are done either way (IEEE `0 x` is not folded).
    wm: Matrix3<f64>,
}

/// `δ(x, y)` as [`DisparityCorrection::at_normalised`] computes it (the same expression),
/// inlined.
#[inline(always)]
fn correction_at(c: &DisparityCorrection, x: f64, y: f64) -> f64 {
    DisparityCorrection::basis(x, y)
        .iter()
        .zip(c.coefficients())
        .map(|(b, c)| b * c)
        .sum()
}

impl Prepared {
    /// `model` with its constants.
    #[inline(always)]
    pub(crate) fn new(model: &StereoModel) -> Self {
        let (p, d) = (model.noise.position_px, model.noise.disparity_px);
        let w = Vector3::new(1.0 / p, 1.0 / p, 1.0 / d);
        Self {
            model: *model,
            fb: model.rig.fx * model.rig.baseline_m,
            w,
            wm: std::hint::black_box(Matrix3::from_diagonal(&w)),
        }
    }

    /// [`StereoModel::anchor`].
    #[inline(always)]
    pub(crate) fn anchor(&self, z: &StereoObservation) -> Vector3<f64> {
        let r = &self.model.rig;
        let x = (z.u - r.cx) / r.fx;
        let y = (z.v - r.cy) / r.fy;
        let b = r.baseline_m;
        let mut rho = z.d / self.fb;
        for _ in 0..4 {
            rho = (z.d + correction_at(&self.model.correction, x - b * rho, y)) / self.fb;
        }
        Vector3::new(x, y, rho)
    }

    /// `StereoModel::calibration_columns`.
    #[inline(always)]
    fn calibration_columns(&self, x: f64, y: f64, xr: f64, rho_z: f64) -> Matrix3xK {
        let r = &self.model.rig;
        let mut m = Matrix3xK::zeros();
        for (k, b) in DisparityCorrection::basis(xr, y).iter().enumerate() {
            m[(2, k)] = -b;
        }
        m[(0, FOCAL_TERM)] = x;
        m[(1, FOCAL_TERM)] = y * r.fy / r.fx;
        m[(2, FOCAL_TERM)] = r.baseline_m * rho_z;
        m
    }

    /// [`StereoModel::residuals2`].
    #[inline(always)]
    pub(crate) fn residuals2(
        &self,
        rot: &Matrix3<f64>,
        trans: &Vector3<f64>,
        p: &Vector3<f64>,
        a: &StereoObservation,
        b: &StereoObservation,
    ) -> Option<(f64, f64)> {
        Some((
            self.residual2_in_reference(p, a),
            self.residual2_in_current(rot, trans, p, b)?,
        ))
    }

    /// [`StereoModel::residual2_in_reference`].
    #[inline(always)]
    pub(crate) fn residual2_in_reference(&self, p: &Vector3<f64>, a: &StereoObservation) -> f64 {
        let r = &self.model.rig;
        let rho = p.z;
        let e = Vector3::new(
            r.fx * p.x + r.cx - a.u,
            r.fy * p.y + r.cy - a.v,
            self.fb * rho
                - correction_at(&self.model.correction, p.x - r.baseline_m * rho, p.y)
                - a.d,
        );
        e.component_mul(&self.w).norm_squared()
    }

    /// [`StereoModel::residual2_in_current`].
    #[inline(always)]
    pub(crate) fn residual2_in_current(
        &self,
        rot: &Matrix3<f64>,
        trans: &Vector3<f64>,
        p: &Vector3<f64>,
        b: &StereoObservation,
    ) -> Option<f64> {
        let r = &self.model.rig;
        let rho = p.z;
        let h = rot * Vector3::new(p.x, p.y, 1.0) + trans * rho;
        if h.z <= 1e-9 {
            return None;
        }
        let iz = 1.0 / h.z;
        let (xn, yn) = (h.x * iz, h.y * iz);
        let e = Vector3::new(
            r.fx * xn + r.cx - b.u,
            r.fy * yn + r.cy - b.v,
            self.fb * rho * iz
                - correction_at(&self.model.correction, xn - r.baseline_m * rho * iz, yn)
                - b.d,
        );
        Some(e.component_mul(&self.w).norm_squared())
    }

    /// `StereoModel::in_reference_parts`.
    #[inline(always)]
    pub(crate) fn in_reference_parts(
        &self,
        p: &Vector3<f64>,
        z: &StereoObservation,
        parts: Parts,
    ) -> Linearized {
        let r = &self.model.rig;
        let c = &self.model.correction;
        let b = r.baseline_m;
        let (x, y, rho) = (p.x, p.y, p.z);
        let xr = x - b * rho;
        let (sx, sy) = (c.d_dx(xr, y), c.d_dy(xr));
        let pred = Vector3::new(
            r.fx * x + r.cx,
            r.fy * y + r.cy,
            self.fb * rho - correction_at(c, xr, y),
        );
        let w = self.w;
        let d_point = Matrix3::new(r.fx, 0.0, 0.0, 0.0, r.fy, 0.0, -sx, -sy, self.fb + sx * b);
        let d_correction = if parts == Parts::All {
            self.wm * self.calibration_columns(x, y, xr, rho)
        } else {
            Matrix3xK::zeros()
        };
        Linearized {
            residual: (pred - Vector3::new(z.u, z.v, z.d)).component_mul(&w),
            d_point: self.wm * d_point,
            d_pose: Matrix3x6::zeros(),
            d_correction,
            d_h: Matrix3::zeros(),
        }
    }

    /// `StereoModel::in_current_parts`.
    #[inline(always)]
    pub(crate) fn in_current_parts(
        &self,
        rot: &Matrix3<f64>,
        trans: &Vector3<f64>,
        p: &Vector3<f64>,
        z: &StereoObservation,
        parts: Parts,
    ) -> Option<Linearized> {
        let r = &self.model.rig;
        let c = &self.model.correction;
        let rho = p.z;
        let h = rot * Vector3::new(p.x, p.y, 1.0) + trans * rho;
        if h.z <= 1e-9 {
            return None;
        }
        let iz = 1.0 / h.z;
        let b = r.baseline_m;
        let (xn, yn) = (h.x * iz, h.y * iz);
        let xr = xn - b * rho * iz;
        let (sx, sy) = (c.d_dx(xr, yn), c.d_dy(xr));
        let pred = Vector3::new(
            r.fx * xn + r.cx,
            r.fy * yn + r.cy,
            self.fb * rho * iz - correction_at(c, xr, yn),
        );
        let dh = Matrix3::new(
            r.fx * iz,
            0.0,
            -r.fx * xn * iz,
            0.0,
            r.fy * iz,
            -r.fy * yn * iz,
            -sx * iz,
            -sy * iz,
            -self.fb * rho * iz * iz - sx * (-xn * iz + b * rho * iz * iz) + sy * yn * iz,
        );
        let mut dh_dp = Matrix3::zeros();
        dh_dp.set_column(0, &rot.column(0));
        dh_dp.set_column(1, &rot.column(1));
        dh_dp.set_column(2, trans);
        let mut d_point = dh * dh_dp;
        d_point[(2, 2)] += self.fb * iz + sx * b * iz;
        let w = self.wm;
        let d_pose = if parts == Parts::Point {
            Matrix3x6::zeros()
        } else {
            let mut dh_dxi = Matrix3x6::zeros();
            dh_dxi
                .fixed_view_mut::<3, 3>(0, 0)
                .copy_from(&(Matrix3::identity() * rho));
            dh_dxi
                .fixed_view_mut::<3, 3>(0, 3)
                .copy_from(&(-h.cross_matrix()));
            w * dh * dh_dxi
        };
        let (d_correction, d_h) = if parts == Parts::All {
            (w * self.calibration_columns(xn, yn, xr, rho * iz), w * dh)
        } else {
            (Matrix3xK::zeros(), Matrix3::zeros())
        };
        Some(Linearized {
            residual: w * (pred - Vector3::new(z.u, z.v, z.d)),
            d_point: w * d_point,
            d_pose,
            d_correction,
            d_h,
        })
    }
}

#[cfg(test)]
#[path = "prepared_tests.rs"]
mod tests;
