//! Stereo-noise scenarios: what a stereo rig hands a registration, not isotropic noise.
//!
//! Each scene point is seen by a rectified stereo pair at two poses. Its 3D position in
//! each camera frame is **triangulated from noisy pixels** `(u, v, disparity)`, so the
//! noise grows with the square of the depth and lies along the viewing ray; the
//! covariance of each triangulated point (first-order propagation of the pixel noise,
//! evaluated at the noisy measurement, as a real system would) is attached. Wrong matches
//! pair a point's source with the destination of **another real point of the scene**
//! (not a uniform draw in a box), so they follow the scene's structure.
//!
//! Frames: camera 1 (destination) and camera 2 (source), `x` right, `y` down, `z`
//! forward; `dst = R src + t`. Sizes: [`StereoSpec::street`] (3-40 m deep, 0.54 m
//! baseline, KITTI-like), [`StereoSpec::room`] and [`StereoSpec::tabletop`] (the same
//! rig and pixel noise scaled down), each in any length unit ([`StereoSpec::unit`]).

use nalgebra::{Isometry3, Matrix3, Point3, Translation3, Vector3};
use rand::RngExt;
use rand_distr::{Distribution, StandardNormal};
use swarmpose_core::geometry::rotation_angle_between;
use swarmpose_core::rng::seeded;
use swarmpose_core::{Correspondences, SeededRng};

use crate::error::SimError;
use swarmpose_core::synthetic::random_motion;

/// Most draws of scene points per wanted point before giving up.
const MAX_DRAWS_PER_POINT: usize = 200;

/// Least noisy disparity kept, pixels: a point matched at smaller disparity is dropped
/// and drawn again (its depth would be unbounded).
const MIN_DISPARITY_PX: f64 = 1.0;

/// Settings of a stereo-noise scenario. Defaults are [`StereoSpec::street`].
#[derive(Debug, Clone, PartialEq)]
pub struct StereoSpec {
    /// Correspondences \[600\].
    pub n: usize,
    /// Fraction of wrong matches, in `[0, 1)` \[0.9\].
    pub outlier_fraction: f64,
    /// Depth range of the scene points in camera 1, metres (before `unit`) [3, 40].
    pub depth_m: [f64; 2],
    /// Stereo baseline, metres \[0.54\].
    pub baseline_m: f64,
    /// Focal length, pixels \[600\].
    pub focal_px: f64,
    /// Image width and height, pixels [1000, 800]; the principal point is the centre.
    pub image_px: [f64; 2],
    /// Pixel noise σ of `u`, `v` and each image's column (so the disparity's σ is
    /// `√2` times this), pixels \[0.5\].
    pub pixel_sigma: f64,
    /// Largest rotation of camera 2, degrees \[30\].
    pub max_rotation_deg: f64,
    /// Largest translation of camera 2, metres \[2\].
    pub max_translation_m: f64,
    /// Length unit of the output: coordinates are multiplied by this (1 for metres,
    /// 1000 for millimetres) and covariances by its square \[1\].
    pub unit: f64,
}

impl Default for StereoSpec {
    fn default() -> Self {
        Self::street()
    }
}

impl StereoSpec {
    /// A street seen by a KITTI-like rig: points 3-40 m deep, 0.54 m baseline, camera 2
    /// up to 2 m and 30 degrees away.
    #[must_use]
    pub fn street() -> Self {
        Self {
            n: 600,
            outlier_fraction: 0.9,
            depth_m: [3.0, 40.0],
            baseline_m: 0.54,
            focal_px: 600.0,
            image_px: [1000.0, 800.0],
            pixel_sigma: 0.5,
            max_rotation_deg: 30.0,
            max_translation_m: 2.0,
            unit: 1.0,
        }
    }

    /// The street rig scaled by `factor` (depths, baseline and translation; the pixels
    /// and their noise are unchanged, so the noise scales too).
    #[must_use]
    pub fn scaled(factor: f64) -> Self {
        let s = Self::street();
        Self {
            depth_m: [s.depth_m[0] * factor, s.depth_m[1] * factor],
            baseline_m: s.baseline_m * factor,
            max_translation_m: s.max_translation_m * factor,
            ..s
        }
    }

    /// A room: the street scaled by 0.15 (points 0.45-6 m deep, 8 cm baseline).
    #[must_use]
    pub fn room() -> Self {
        Self::scaled(0.15)
    }

    /// A tabletop: the street scaled by 0.008 (points 2.4-32 cm deep, 4.3 mm baseline;
    /// scene extent under 0.5 m).
    #[must_use]
    pub fn tabletop() -> Self {
        Self::scaled(0.008)
    }

    /// Sets the outlier fraction.
    #[must_use]
    pub fn with_outliers(mut self, fraction: f64) -> Self {
        self.outlier_fraction = fraction;
        self
    }

    /// Sets the output unit (1000 for millimetres).
    #[must_use]
    pub fn with_unit(mut self, unit: f64) -> Self {
        self.unit = unit;
        self
    }

    /// Sets the number of correspondences.
    #[must_use]
    pub fn with_n(mut self, n: usize) -> Self {
        self.n = n;
        self
    }

    /// Checks the settings.
    ///
    /// # Errors
    /// [`SimError::InvalidConfig`] naming the bad setting.
    pub fn validate(&self) -> Result<(), SimError> {
        let positive = [
            ("baseline_m", self.baseline_m),
            ("focal_px", self.focal_px),
            ("image width", self.image_px[0]),
            ("image height", self.image_px[1]),
            ("unit", self.unit),
            ("near depth", self.depth_m[0]),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(SimError::InvalidConfig(format!(
                    "{name} must be positive and finite, got {v}"
                )));
            }
        }
        let non_negative = [
            ("pixel_sigma", self.pixel_sigma),
            ("max_rotation_deg", self.max_rotation_deg),
            ("max_translation_m", self.max_translation_m),
        ];
        for (name, v) in non_negative {
            if !(v.is_finite() && v >= 0.0) {
                return Err(SimError::InvalidConfig(format!(
                    "{name} must be finite and >= 0, got {v}"
                )));
            }
        }
        if !(self.depth_m[1].is_finite() && self.depth_m[1] > self.depth_m[0]) {
            return Err(SimError::InvalidConfig(
                "depth range must have near < far".into(),
            ));
        }
        if !(0.0..1.0).contains(&self.outlier_fraction) {
            return Err(SimError::InvalidConfig(format!(
                "outlier fraction must be in [0, 1), got {}",
                self.outlier_fraction
            )));
        }
        if self.n < 4 {
            return Err(SimError::InvalidConfig("n must be at least 4".into()));
        }
        Ok(())
    }

    /// Pixel and disparity of a point (camera frame, metres) if the rig sees it in both
    /// images of the pair.
    fn observe(&self, p: &Point3<f64>) -> Option<[f64; 3]> {
        if p.z <= self.depth_m[0] * 0.5 {
            return None;
        }
        let (cx, cy) = (self.image_px[0] / 2.0, self.image_px[1] / 2.0);
        let u = self.focal_px * p.x / p.z + cx;
        let v = self.focal_px * p.y / p.z + cy;
        let d = self.focal_px * self.baseline_m / p.z;
        let inside = (0.0..self.image_px[0]).contains(&u)
            && (0.0..self.image_px[0]).contains(&(u - d))
            && (0.0..self.image_px[1]).contains(&v);
        inside.then_some([u, v, d])
    }

    /// Triangulates noisy pixels of `p`: the point and its covariance (metres, m²), or
    /// `None` when the noisy disparity is too small.
    fn triangulate(
        &self,
        p: &Point3<f64>,
        rng: &mut SeededRng,
    ) -> Option<(Point3<f64>, Matrix3<f64>)> {
        let [u, v, d] = self.observe(p)?;
        let s = self.pixel_sigma;
        let mut noise = || -> f64 { StandardNormal.sample(rng) };
        let (u, v) = (u + s * noise(), v + s * noise());
        // Disparity: the difference of two independently noisy columns.
        let d = d + s * noise() - s * noise();
        if d < MIN_DISPARITY_PX {
            return None;
        }
        let (f, (cx, cy)) = (
            self.focal_px,
            (self.image_px[0] / 2.0, self.image_px[1] / 2.0),
        );
        let z = f * self.baseline_m / d;
        let (x, y) = ((u - cx) * z / f, (v - cy) * z / f);
        // ∂(x, y, z)/∂(u, v, d).
        let j = Matrix3::new(z / f, 0.0, -x / d, 0.0, z / f, -y / d, 0.0, 0.0, -z / d);
        let pixel_cov = Matrix3::from_diagonal(&Vector3::new(s * s, s * s, 2.0 * s * s));
        // A floor far below any noise keeps the matrix positive definite at σ = 0.
        let floor = Matrix3::identity() * (1e-9 * z).powi(2);
        Some((Point3::new(x, y, z), j * pixel_cov * j.transpose() + floor))
    }

    /// The scenario of `seed`.
    ///
    /// # Errors
    /// [`SimError::InvalidConfig`] for bad settings or a rig that sees too few points.
    pub fn scenario(&self, seed: u64) -> Result<StereoScenario, SimError> {
        self.validate()?;
        let mut rng = seeded(seed);
        let angle = rng.random_range(0.0..=self.max_rotation_deg).to_radians();
        let truth = random_motion(&mut rng, angle, self.max_translation_m);
        let (mut src, mut dst, mut src_cov, mut dst_cov) = (vec![], vec![], vec![], vec![]);
        let (w, h) = (self.image_px[0], self.image_px[1]);
        let (cx, cy) = (w / 2.0, h / 2.0);
        let mut draws = 0;
        while src.len() < self.n {
            draws += 1;
            if draws > MAX_DRAWS_PER_POINT * self.n {
                return Err(SimError::InvalidConfig(format!(
                    "the rig saw only {} of {} points in both poses",
                    src.len(),
                    self.n
                )));
            }
            // Uniform in the image and in depth.
            let z = rng.random_range(self.depth_m[0]..self.depth_m[1]);
            let (u, v) = (rng.random_range(0.0..w), rng.random_range(0.0..h));
            let p1 = Point3::new(
                (u - cx) * z / self.focal_px,
                (v - cy) * z / self.focal_px,
                z,
            );
            let p2 = truth.inverse_transform_point(&p1);
            let (Some((d, dc)), Some((s, sc))) = (
                self.triangulate(&p1, &mut rng),
                self.triangulate(&p2, &mut rng),
            ) else {
                continue;
            };
            src.push(s);
            src_cov.push(sc);
            dst.push(d);
            dst_cov.push(dc);
        }
        // Wrong matches: the destination (and its covariance) of another scene point.
        let n_out = (self.outlier_fraction * self.n as f64).round() as usize;
        let mut inlier = vec![true; self.n];
        let wrong = rand::seq::index::sample(&mut rng, self.n, n_out).into_vec();
        let (dst0, dc0) = (dst.clone(), dst_cov.clone());
        for &i in &wrong {
            let mut j = rng.random_range(0..self.n - 1);
            if j >= i {
                j += 1;
            }
            dst[i] = dst0[j];
            dst_cov[i] = dc0[j];
            inlier[i] = false;
        }
        let k = self.unit;
        let scale_p = |v: Vec<Point3<f64>>| v.into_iter().map(|p| p * k).collect::<Vec<_>>();
        let scale_c = |v: Vec<Matrix3<f64>>| v.into_iter().map(|c| c * (k * k)).collect::<Vec<_>>();
        let truth = Isometry3::from_parts(
            Translation3::from(truth.translation.vector * k),
            truth.rotation,
        );
        let data = Correspondences::new(scale_p(src), scale_p(dst))?
            .with_noise_covariance(scale_c(src_cov), scale_c(dst_cov))?;
        Ok(StereoScenario {
            data,
            truth,
            inlier,
            success_translation: 0.2 * self.depth_m[1] / 40.0 * k,
        })
    }
}

/// One stereo-noise problem and what is known about it.
#[derive(Debug, Clone, PartialEq)]
pub struct StereoScenario {
    /// The correspondences with their noise covariances, in the spec's unit.
    pub data: Correspondences,
    /// The true motion, `dst = R src + t`, in the spec's unit.
    pub truth: Isometry3<f64>,
    /// `inlier[i]` is false where correspondence `i` is a wrong match.
    pub inlier: Vec<bool>,
    /// Largest translation error of a success, in the spec's unit: 0.2 m for the street
    /// (as the bench), scaled with the scene.
    pub success_translation: f64,
}

impl StereoScenario {
    /// The same points without the noise model (plain coordinates).
    ///
    /// # Errors
    /// None in practice: the points were valid with the noise model.
    pub fn plain(&self) -> Result<Correspondences, SimError> {
        Ok(Correspondences::new(
            self.data.src().to_vec(),
            self.data.dst().to_vec(),
        )?)
    }

    /// Indices of the true inliers, ascending.
    #[must_use]
    pub fn inlier_indices(&self) -> Vec<usize> {
        (0..self.inlier.len()).filter(|&i| self.inlier[i]).collect()
    }

    /// Whether `pose` is a success: rotation error under 2 degrees and translation error
    /// under [`StereoScenario::success_translation`].
    #[must_use]
    pub fn is_success(&self, pose: &Isometry3<f64>) -> bool {
        rotation_angle_between(&pose.rotation, &self.truth.rotation).to_degrees() < 2.0
            && (pose.translation.vector - self.truth.translation.vector).norm()
                < self.success_translation
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inliers_follow_the_motion_within_their_covariance() {
        let spec = StereoSpec::street().with_outliers(0.5);
        let s = spec.scenario(3).expect("valid");
        assert_eq!(s.data.len(), 600);
        assert_eq!(s.inlier.iter().filter(|&&b| !b).count(), 300);
        let (sc, dc) = s.data.noise_covariance().expect("attached");
        let r = s.truth.rotation.to_rotation_matrix();
        let mut chi2 = Vec::new();
        for i in s.inlier_indices() {
            let e = s.data.dst()[i] - s.truth * s.data.src()[i];
            let cov = r.matrix() * sc[i] * r.matrix().transpose() + dc[i];
            let w = cov.try_inverse().expect("positive definite");
            chi2.push(e.dot(&(w * e)));
        }
        // Mean of χ²(3) is 3 (first-order propagation: allow a little bias).
        let mean = chi2.iter().sum::<f64>() / chi2.len() as f64;
        assert!((2.4..3.8).contains(&mean), "mean χ² {mean}");
        // Depth noise grows with depth: far points are noisier than near ones.
        let sigma = s.data.noise_sigma().expect("derived");
        let (near, far): (Vec<usize>, Vec<usize>) = s
            .inlier_indices()
            .iter()
            .partition(|&&i| s.data.dst()[i].z < 10.0);
        let mean_of = |v: &[usize]| v.iter().map(|&i| sigma[i]).sum::<f64>() / v.len() as f64;
        let (a, b) = (mean_of(&far), mean_of(&near));
        assert!(a > 5.0 * b, "far {a} near {b}");
    }

    #[test]
    fn wrong_matches_land_on_other_scene_points_and_units_scale() {
        let spec = StereoSpec::tabletop().with_outliers(0.9);
        let m = spec.scenario(5).expect("valid");
        let mm = spec.clone().with_unit(1000.0).scenario(5).expect("valid");
        for i in 0..m.data.len() {
            let d = mm.data.dst()[i] - m.data.dst()[i] * 1000.0;
            assert!(d.norm() < 1e-9 * 1000.0);
        }
        assert!((mm.truth.translation.vector - m.truth.translation.vector * 1000.0).norm() < 1e-9);
        // Extent under 0.5 m, and every wrong destination is some other point's.
        assert!(m.data.dst().iter().all(|p| p.coords.amax() < 0.5));
        let wrong: Vec<usize> = (0..600).filter(|&i| !m.inlier[i]).collect();
        assert_eq!(wrong.len(), 540);
        assert!(spec.clone().with_outliers(1.0).scenario(1).is_err());
    }
}
