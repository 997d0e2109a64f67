//! Seeded synthetic correspondences with a known motion, for tests, benchmarks and
//! demonstrations (no I/O).
//!
//! Scene points are uniform in a box (metres, destination frame); the truth motion has a
//! rotation of angle uniform in `[0, max_rotation_rad]` about a uniform axis and a
//! translation of length uniform in `[0, max_translation_m]` in a uniform direction;
//! `src = R^T (dst - t)`, so `dst = R src + t`; Gaussian noise of σ per axis is added to
//! `dst`; a fraction of the rows is then replaced by a uniform box point (a wrong match).
//! This mirrors `gen_scenarios.py`'s `random` mode without the camera visibility test.

use nalgebra::{Isometry3, Point3, Translation3, Unit, UnitQuaternion, Vector3};
use rand::RngExt;
use rand_distr::{Distribution, Normal, StandardNormal};

use crate::error::PoseError;
use crate::geometry::Correspondences;
use crate::rng::{SeededRng, seeded};

/// What to generate. Defaults in brackets.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticSpec {
    /// Number of correspondences \[200\].
    pub n: usize,
    /// Gaussian noise σ per axis on `dst`, metres [0.02].
    pub noise_sigma_m: f64,
    /// Fraction of correspondences that are wrong matches, in `[0, 1]` \[0\].
    pub outlier_fraction: f64,
    /// Largest rotation angle, radians [20° = 0.349].
    pub max_rotation_rad: f64,
    /// Largest translation, metres [1.5].
    pub max_translation_m: f64,
    /// Lower corner of the scene box, metres [(-6, -6, 2)].
    pub box_lo: [f64; 3],
    /// Upper corner of the scene box, metres [(6, 6, 25)].
    pub box_hi: [f64; 3],
}

impl Default for SyntheticSpec {
    fn default() -> Self {
        Self {
            n: 200,
            noise_sigma_m: 0.02,
            outlier_fraction: 0.0,
            max_rotation_rad: 20f64.to_radians(),
            max_translation_m: 1.5,
            box_lo: [-6.0, -6.0, 2.0],
            box_hi: [6.0, 6.0, 25.0],
        }
    }
}

/// A generated problem and its truth.
#[derive(Debug, Clone, PartialEq)]
pub struct SyntheticScenario {
    /// The correspondences.
    pub data: Correspondences,
    /// The true motion, `dst = R src + t` on inliers.
    pub truth: Isometry3<f64>,
    /// `inlier[i]` is false where row `i` is a wrong match.
    pub inlier: Vec<bool>,
}

/// A uniformly distributed unit vector (a normalised standard normal draw).
pub fn random_unit(rng: &mut SeededRng) -> Unit<Vector3<f64>> {
    loop {
        let v = Vector3::new(
            StandardNormal.sample(rng),
            StandardNormal.sample(rng),
            StandardNormal.sample(rng),
        );
        if v.norm() > 1e-9 {
            return Unit::new_normalize(v);
        }
    }
}

/// A motion rotating by `angle_rad` about a uniform random axis, then translating along a
/// uniform random direction by a uniform length in `[0, max_translation_m]` metres (drawn
/// in that order).
pub fn random_motion(
    rng: &mut SeededRng,
    angle_rad: f64,
    max_translation_m: f64,
) -> Isometry3<f64> {
    let rotation = UnitQuaternion::from_axis_angle(&random_unit(rng), angle_rad);
    let t = random_unit(rng).into_inner() * rng.random_range(0.0..=max_translation_m);
    Isometry3::from_parts(Translation3::from(t), rotation)
}

impl SyntheticSpec {
    /// Generates the scenario of `seed`.
    ///
    /// # Errors
    /// [`PoseError::InvalidConfig`] for a negative or non-finite noise, a fraction outside
    /// `[0, 1]` or an empty box.
    pub fn generate(&self, seed: u64) -> Result<SyntheticScenario, PoseError> {
        if !(self.noise_sigma_m.is_finite() && self.noise_sigma_m >= 0.0) {
            return Err(PoseError::InvalidConfig("noise must be >= 0".into()));
        }
        if !(0.0..=1.0).contains(&self.outlier_fraction) {
            return Err(PoseError::InvalidConfig(
                "outlier fraction must be in [0, 1]".into(),
            ));
        }
        if (0..3)
            .any(|k| self.box_lo[k].partial_cmp(&self.box_hi[k]) != Some(std::cmp::Ordering::Less))
        {
            return Err(PoseError::InvalidConfig("box must have lo < hi".into()));
        }
        let mut rng = seeded(seed);
        let angle = rng.random_range(0.0..=self.max_rotation_rad.max(0.0));
        let truth = random_motion(&mut rng, angle, self.max_translation_m.max(0.0));
        let noise = Normal::new(0.0, self.noise_sigma_m)
            .map_err(|e| PoseError::InvalidConfig(e.to_string()))?;
        let box_point = |rng: &mut crate::rng::SeededRng| {
            Point3::new(
                rng.random_range(self.box_lo[0]..self.box_hi[0]),
                rng.random_range(self.box_lo[1]..self.box_hi[1]),
                rng.random_range(self.box_lo[2]..self.box_hi[2]),
            )
        };
        let mut src = Vec::with_capacity(self.n);
        let mut dst = Vec::with_capacity(self.n);
        for _ in 0..self.n {
            let d = box_point(&mut rng);
            src.push(truth.inverse_transform_point(&d));
            let jitter = Vector3::new(
                noise.sample(&mut rng),
                noise.sample(&mut rng),
                noise.sample(&mut rng),
            );
            dst.push(d + jitter);
        }
        let n_out = (self.outlier_fraction * self.n as f64).round() as usize;
        let mut inlier = vec![true; self.n];
        for i in rand::seq::index::sample(&mut rng, self.n, n_out.min(self.n)) {
            dst[i] = box_point(&mut rng);
            inlier[i] = false;
        }
        Ok(SyntheticScenario {
            data: Correspondences::new(src, dst)?,
            truth,
            inlier,
        })
    }
}
