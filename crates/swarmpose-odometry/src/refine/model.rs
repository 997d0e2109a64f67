//! The stereo measurement model of the reprojection refinement, with its Jacobians.
//!
//! A rectified stereo camera measures a point as its left pixel and its disparity,
//! `z = (u, v, d)`, pixels. Points are anchored in the reference frame A by inverse depth,
//! `p = (x, y, ρ)` with `P_A = (x, y, 1) / ρ` (metres, left camera of A): `x`, `y` are the
//! normalised image coordinates and `ρ = 1 / Z_A` (1/m), so points at infinity (`ρ = 0`)
//! are represented exactly and A's own measurement is linear in `p`:
//!
//! ```text
//! u_A = fx x + cx,   v_A = fy y + cy,   d_A = fx b ρ − δ(x, y)
//! ```
//!
//! The current frame B sees `P_B = R P_A + t` (`(R, t)` the pose of A in B, `T_BA`). With
//! `h = ρ P_B = R (x, y, 1) + ρ t` (finite for `ρ = 0`):
//!
//! ```text
//! u_B = fx h_x / h_z + cx,   v_B = fy h_y / h_z + cy,   d_B = fx b ρ / h_z − δ(h_x / h_z, h_y / h_z)
//! ```
//!
//! `δ(x_r, y)` is the disparity correction (a measured disparity is short of the true one
//! by `δ`; see [`swarmpose_vision::frontend::DisparityCorrection`]), a function of the
//! right image point `x_r = x − b ρ` (A) or `x_r = h_x / h_z − b ρ / h_z` (B), linear in
//! its coefficients `c` (the model's third row depends on them through `−φ(x_r, y)ᵀ c`). A pose
//! perturbation `ξ = (ν, ω)` acts as `P_B ← Exp(ω) P_B + ν`, so `∂h/∂ν = ρ I` and
//! `∂h/∂ω = −[h]×`.

use nalgebra::{Matrix3, SMatrix, Vector3};
use swarmpose_vision::frontend::{CORRECTION_TERMS, DisparityCorrection};
use swarmpose_vision::stereo::RectifiedStereo;

/// One stereo measurement of a point: left pixel `(u, v)` and disparity `d`, pixels, as
/// measured (before any disparity correction).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StereoObservation {
    /// Left image column, pixels.
    pub u: f64,
    /// Left image row, pixels.
    pub v: f64,
    /// Disparity `u_left − u_right`, pixels.
    pub d: f64,
}

/// Standard deviations of a stereo measurement, pixels: `position_px` for `u` and `v`,
/// `disparity_px` for `d` (the disparity is refined on an image window, so it is more
/// precise than the keypoint position, whose error is common to both images).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(deny_unknown_fields)
)]
pub struct PixelNoise {
    /// Standard deviation of `u` and `v`, pixels.
    pub position_px: f64,
    /// Standard deviation of `d`, pixels.
    pub disparity_px: f64,
}

/// The rig and noise of the measurements, and the disparity correction applied.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StereoModel {
    /// The rectified stereo camera.
    pub rig: RectifiedStereo,
    /// Measurement noise.
    pub noise: PixelNoise,
    /// Disparity correction `δ(x) = a + q x²`.
    pub correction: DisparityCorrection,
}

/// 3x6 matrix.
pub type Matrix3x6 = SMatrix<f64, 3, 6>;
/// Number of calibration terms the evidence is about: the [`CORRECTION_TERMS`]
/// coefficients of the disparity correction, then the focal length of the rig.
pub const CALIBRATION_TERMS: usize = CORRECTION_TERMS + 1;
/// Index of the focal length among the calibration terms: a change `Δf` of `fx`, pixels,
/// with `fy` changed in proportion (`fy (1 + Δf / fx)`) and the baseline unchanged.
pub const FOCAL_TERM: usize = CORRECTION_TERMS;
/// 3xK matrix, K the number of calibration terms.
pub type Matrix3xK = SMatrix<f64, 3, CALIBRATION_TERMS>;

/// Which Jacobians a linearisation computes (the residual and `∂e/∂p` always): the
/// refinement's inner loops need fewer than the evidence.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum Parts {
    /// The point's only: fitting a point to a fixed pose.
    Point,
    /// The point's and the pose's: Levenberg-Marquardt on the pose.
    PointPose,
    /// Every Jacobian, with the calibration terms.
    All,
}

/// Whitened residual and Jacobians of one measurement: `e = (z_pred − z) / σ`.
#[derive(Debug, Clone, Copy)]
pub struct Linearized {
    /// Whitened residual.
    pub residual: Vector3<f64>,
    /// `∂e/∂p` for the point `(x, y, ρ)`.
    pub d_point: Matrix3<f64>,
    /// `∂e/∂ξ` for the pose perturbation `(ν, ω)` (zero for frame A).
    pub d_pose: Matrix3x6,
    /// `∂e/∂c` for the calibration terms (disparity correction, focal length).
    pub d_correction: Matrix3xK,
    /// `∂e/∂h` for `h = ρ P_B` (zero for frame A): with `∂h/∂(anything)` it gives the
    /// Jacobian of any other parametrisation of the pose (the window's, [`crate::window`]).
    pub d_h: Matrix3<f64>,
}

impl StereoModel {
    #[inline(always)]
    fn fb(&self) -> f64 {
        self.rig.fx * self.rig.baseline_m
    }

    #[inline(always)]
    fn whiten(&self) -> Vector3<f64> {
        let (p, d) = (self.noise.position_px, self.noise.disparity_px);
        Vector3::new(1.0 / p, 1.0 / p, 1.0 / d)
    }

    /// The anchored inverse-depth point of a measurement in frame A, with the correction
    /// applied: `x = (u − cx)/fx`, `y = (v − cy)/fy`, and `ρ` solving
    /// `fx b ρ − δ(x − b ρ, y) = d` (a few fixed-point steps from the uncorrected value).
    #[must_use]
    #[inline(always)]
    pub fn anchor(&self, z: &StereoObservation) -> Vector3<f64> {
        let x = (z.u - self.rig.cx) / self.rig.fx;
        let y = (z.v - self.rig.cy) / self.rig.fy;
        let b = self.rig.baseline_m;
        let mut rho = z.d / self.fb();
        for _ in 0..4 {
            rho = (z.d + self.correction.at_normalised(x - b * rho, y)) / self.fb();
        }
        Vector3::new(x, y, rho)
    }

    /// `∂e/∂c` before whitening: `−φ(x_r, y)` for the disparity's correction terms, and
    /// for the focal length (`fx + Δf`, `fy (1 + Δf / fx)`) `(x, y fy / fx, b ρ / h_z)`
    /// at the normalised point `(x, y)` of the left image and inverse depth over `h_z`
    /// `rho_z` (`ρ` in A, `ρ / h_z` in B).
    #[inline(always)]
    fn calibration_columns(&self, x: f64, y: f64, xr: f64, rho_z: f64) -> Matrix3xK {
        let mut m = Matrix3xK::zeros();
        for (k, b) in DisparityCorrection::basis(xr, y).iter().enumerate() {
            m[(2, k)] = -b;
        }
        m[(0, FOCAL_TERM)] = x;
        m[(1, FOCAL_TERM)] = y * self.rig.fy / self.rig.fx;
        m[(2, FOCAL_TERM)] = self.rig.baseline_m * rho_z;
        m
    }

    /// Squared norms of the whitened residuals of `p` in A and in B (no Jacobians), or
    /// `None` when the point is not in front of camera B.
    #[must_use]
    #[inline(always)]
    pub fn residuals2(
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

    /// Squared norm of the whitened residual of `p` in A.
    #[must_use]
    #[inline(always)]
    pub fn residual2_in_reference(&self, p: &Vector3<f64>, a: &StereoObservation) -> f64 {
        let r = &self.rig;
        let rho = p.z;
        let e = Vector3::new(
            r.fx * p.x + r.cx - a.u,
            r.fy * p.y + r.cy - a.v,
            self.fb() * rho - self.correction.at_normalised(p.x - r.baseline_m * rho, p.y) - a.d,
        );
        e.component_mul(&self.whiten()).norm_squared()
    }

    /// Squared norm of the whitened residual of `p` in B for the pose `(rot, trans)` of A
    /// in B, or `None` when the point is not in front of camera B.
    #[must_use]
    #[inline(always)]
    pub fn residual2_in_current(
        &self,
        rot: &Matrix3<f64>,
        trans: &Vector3<f64>,
        p: &Vector3<f64>,
        b: &StereoObservation,
    ) -> Option<f64> {
        let r = &self.rig;
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
            self.fb() * rho * iz
                - self
                    .correction
                    .at_normalised(xn - r.baseline_m * rho * iz, yn)
                - b.d,
        );
        Some(e.component_mul(&self.whiten()).norm_squared())
    }

    /// The measurement in frame A of the point `p`: whitened residual and Jacobians.
    #[must_use]
    #[inline(always)]
    pub fn in_reference(&self, p: &Vector3<f64>, z: &StereoObservation) -> Linearized {
        self.in_reference_parts(p, z, Parts::All)
    }

    /// [`StereoModel::in_reference`] computing only the Jacobians of `parts` (the others
    /// zero); those computed are bit for bit the same.
    #[inline(always)]
    pub(crate) fn in_reference_parts(
        &self,
        p: &Vector3<f64>,
        z: &StereoObservation,
        parts: Parts,
    ) -> Linearized {
        let r = &self.rig;
        let c = &self.correction;
        let b = r.baseline_m;
        let (x, y, rho) = (p.x, p.y, p.z);
        let xr = x - b * rho;
        let (sx, sy) = (c.d_dx(xr, y), c.d_dy(xr));
        let pred = Vector3::new(
            r.fx * x + r.cx,
            r.fy * y + r.cy,
            self.fb() * rho - c.at_normalised(xr, y),
        );
        let w = self.whiten();
        let d_point = Matrix3::new(r.fx, 0.0, 0.0, 0.0, r.fy, 0.0, -sx, -sy, self.fb() + sx * b);
        let d_correction = if parts == Parts::All {
            Matrix3::from_diagonal(&w) * self.calibration_columns(x, y, xr, rho)
        } else {
            Matrix3xK::zeros()
        };
        Linearized {
            residual: (pred - Vector3::new(z.u, z.v, z.d)).component_mul(&w),
            d_point: Matrix3::from_diagonal(&w) * d_point,
            d_pose: Matrix3x6::zeros(),
            d_correction,
            d_h: Matrix3::zeros(),
        }
    }

    /// The measurement in frame B of the point `p` for the pose `(rot, trans)` of A in B
    /// (`P_B = rot P_A + trans`), or `None` when the point is not in front of camera B.
    #[must_use]
    #[inline(always)]
    pub fn in_current(
        &self,
        rot: &Matrix3<f64>,
        trans: &Vector3<f64>,
        p: &Vector3<f64>,
        z: &StereoObservation,
    ) -> Option<Linearized> {
        self.in_current_parts(rot, trans, p, z, Parts::All)
    }

    /// [`StereoModel::in_current`] computing only the Jacobians of `parts` (the others
    /// zero); those computed are bit for bit the same.
    #[inline(always)]
    pub(crate) fn in_current_parts(
        &self,
        rot: &Matrix3<f64>,
        trans: &Vector3<f64>,
        p: &Vector3<f64>,
        z: &StereoObservation,
        parts: Parts,
    ) -> Option<Linearized> {
        let r = &self.rig;
        let c = &self.correction;
        let rho = p.z;
        let h = rot * Vector3::new(p.x, p.y, 1.0) + trans * rho;
        if h.z <= 1e-9 {
            return None;
        }
        let iz = 1.0 / h.z;
        let b = r.baseline_m;
        let (xn, yn) = (h.x * iz, h.y * iz);
        // The right image point: x_r = xn − b ρ / h_z.
        let xr = xn - b * rho * iz;
        let (sx, sy) = (c.d_dx(xr, yn), c.d_dy(xr));
        let pred = Vector3::new(
            r.fx * xn + r.cx,
            r.fy * yn + r.cy,
            self.fb() * rho * iz - c.at_normalised(xr, yn),
        );
        // ∂pred/∂h: ∂x_r/∂h = (iz, 0, −xn iz + b ρ iz²), ∂yn/∂h = (0, iz, −yn iz).
        let dh = Matrix3::new(
            r.fx * iz,
            0.0,
            -r.fx * xn * iz,
            0.0,
            r.fy * iz,
            -r.fy * yn * iz,
            -sx * iz,
            -sy * iz,
            -self.fb() * rho * iz * iz - sx * (-xn * iz + b * rho * iz * iz) + sy * yn * iz,
        );
        // ∂h/∂p = [rot e_x, rot e_y, trans]; d also depends on ρ directly.
        let mut dh_dp = Matrix3::zeros();
        dh_dp.set_column(0, &rot.column(0));
        dh_dp.set_column(1, &rot.column(1));
        dh_dp.set_column(2, trans);
        let mut d_point = dh * dh_dp;
        // The direct dependence of d on ρ, through fx b ρ / h_z and x_r.
        d_point[(2, 2)] += self.fb() * iz + sx * b * iz;
        let w = Matrix3::from_diagonal(&self.whiten());
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

/// A KITTI-like rig (`fx` 700, `fy` 690 px, baseline 0.54 m, noise 0.5 / 0.25 px) with
/// `correction`, for tests.
#[cfg(test)]
pub(crate) fn test_model(correction: DisparityCorrection) -> StereoModel {
    StereoModel {
        rig: RectifiedStereo {
            fx: 700.0,
            fy: 690.0,
            cx: 600.0,
            cy: 180.0,
            baseline_m: 0.54,
        },
        noise: PixelNoise {
            position_px: 0.5,
            disparity_px: 0.25,
        },
        correction,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use nalgebra::{Rotation3, UnitQuaternion};

    fn model(correction: DisparityCorrection) -> StereoModel {
        test_model(correction)
    }

    /// Step of the central differences.
    const H: f64 = 1e-6;

    /// A model with every correction term, a pose `(R, t)` of B, a point (by inverse
    /// depth in A) and a measurement in B, for the finite differences.
    fn jacobian_case() -> (
        StereoModel,
        Matrix3<f64>,
        Vector3<f64>,
        Vector3<f64>,
        StereoObservation,
    ) {
        let m = model(DisparityCorrection::from_coefficients([
            0.7, 1.9, -0.4, 0.3, 0.8,
        ]));
        let rot = *Rotation3::from_euler_angles(0.02, -0.05, 0.01).matrix();
        let trans = Vector3::new(0.1, -0.05, -0.9);
        let p = Vector3::new(0.3, -0.1, 1.0 / 12.0);
        let z = StereoObservation {
            u: 812.0,
            v: 111.0,
            d: 31.0,
        };
        (m, rot, trans, p, z)
    }

    /// Central differences of the residual against the analytic Jacobians by the point
    /// and the pose.
    #[test]
    fn jacobians_match_finite_differences() {
        let (m, rot, trans, p, z) = jacobian_case();
        let lin = m.in_current(&rot, &trans, &p, &z).expect("in front");
        let h = H;
        for k in 0..3 {
            let mut dp = Vector3::zeros();
            dp[k] = h;
            let plus = m.in_current(&rot, &trans, &(p + dp), &z).expect("front");
            let minus = m.in_current(&rot, &trans, &(p - dp), &z).expect("front");
            let num = (plus.residual - minus.residual) / (2.0 * h);
            assert!((num - lin.d_point.column(k)).norm() < 1e-4, "point {k}");
        }
        for k in 0..6 {
            let mut xi = [0.0; 6];
            xi[k] = h;
            let moved = |s: f64| {
                let w = Vector3::new(xi[3], xi[4], xi[5]) * s;
                let e = UnitQuaternion::from_scaled_axis(w).to_rotation_matrix();
                let r2 = e.matrix() * rot;
                let t2 = e.matrix() * trans + Vector3::new(xi[0], xi[1], xi[2]) * s;
                m.in_current(&r2, &t2, &p, &z).expect("front").residual
            };
            let num = (moved(1.0) - moved(-1.0)) / (2.0 * h);
            assert!(
                (num - lin.d_pose.column(k)).norm() < 1e-4,
                "pose {k}: {num} vs {}",
                lin.d_pose.column(k)
            );
        }
        let la = m.in_reference(&p, &z);
        for k in 0..3 {
            let mut dp = Vector3::zeros();
            dp[k] = h;
            let num = (m.in_reference(&(p + dp), &z).residual
                - m.in_reference(&(p - dp), &z).residual)
                / (2.0 * h);
            assert!((num - la.d_point.column(k)).norm() < 1e-4);
        }
    }

    /// Central differences of the residual against the analytic Jacobians by the
    /// calibration terms: the disparity correction's and the focal length's.
    #[test]
    fn calibration_jacobians_match_finite_differences() {
        let (m, rot, trans, p, z) = jacobian_case();
        let lin = m.in_current(&rot, &trans, &p, &z).expect("in front");
        let h = H;
        for k in 0..CORRECTION_TERMS {
            let shifted = |s: f64| {
                let mut c = m.correction.coefficients();
                c[k] += s * h;
                let mm = StereoModel {
                    correction: DisparityCorrection::from_coefficients(c),
                    ..m
                };
                (
                    mm.in_current(&rot, &trans, &p, &z).expect("front").residual,
                    mm.in_reference(&p, &z).residual,
                )
            };
            let (bp, ap) = shifted(1.0);
            let (bm, am) = shifted(-1.0);
            assert!(((bp - bm) / (2.0 * h) - lin.d_correction.column(k)).norm() < 1e-4);
            let la = m.in_reference(&p, &z);
            assert!(((ap - am) / (2.0 * h) - la.d_correction.column(k)).norm() < 1e-4);
        }
        // The focal length: fx + Δf and fy in proportion.
        let focal = |s: f64| {
            let mut rig = m.rig;
            rig.fy *= 1.0 + s * h / rig.fx;
            rig.fx += s * h;
            let mm = StereoModel { rig, ..m };
            (
                mm.in_current(&rot, &trans, &p, &z).expect("front").residual,
                mm.in_reference(&p, &z).residual,
            )
        };
        let ((bp, ap), (bm, am)) = (focal(1.0), focal(-1.0));
        let la = m.in_reference(&p, &z);
        let col = lin.d_correction.column(FOCAL_TERM);
        assert!(((bp - bm) / (2.0 * h) - col).norm() < 1e-4, "focal in B");
        let col = la.d_correction.column(FOCAL_TERM);
        assert!(((ap - am) / (2.0 * h) - col).norm() < 1e-4, "focal in A");
    }

    #[test]
    fn residuals_agree_with_the_linearisation() {
        let (m, rot, trans, p, z) = jacobian_case();
        let (a2, b2) = m.residuals2(&rot, &trans, &p, &z, &z).expect("in front");
        let la = m.in_reference(&p, &z);
        let lb = m.in_current(&rot, &trans, &p, &z).expect("in front");
        assert!((a2 - la.residual.norm_squared()).abs() < 1e-9 * (1.0 + a2));
        assert!((b2 - lb.residual.norm_squared()).abs() < 1e-9 * (1.0 + b2));
    }

    #[test]
    fn anchor_inverts_the_reference_measurement() {
        let m = model(DisparityCorrection::from_coefficients([
            1.1, -0.8, 0.2, -0.3, 0.1,
        ]));
        let z = StereoObservation {
            u: 100.0,
            v: 300.0,
            d: 9.5,
        };
        let p = m.anchor(&z);
        assert!(m.in_reference(&p, &z).residual.norm() < 1e-9);
        // Behind camera B: no measurement.
        let behind = m.in_current(
            &Matrix3::identity(),
            &Vector3::new(0.0, 0.0, -100.0),
            &p,
            &z,
        );
        assert!(behind.is_none());
    }
}
