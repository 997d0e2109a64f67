//! Noise and outliers on top of a [`Geometry`]: one simulated problem with its truth.
//!
//! Isotropic Gaussian noise of σ per axis is added to every `dst`; then exactly
//! `round(f N)` correspondences are corrupted, either
//!
//! - [`OutlierMode::Random`]: their `dst` is replaced by a uniform point of the scene box
//!   (a wrong match), or
//! - [`OutlierMode::Structured`]: they are the `round(f N)` visible points nearest a random
//!   visible point, and that object moved rigidly between the frames (rotation
//!   `U[5°, 20°]` about its centroid and translation `U[0.5, 2]` m), so their `src` obey
//!   another rigid motion: a moving object.

use std::fmt;
use std::str::FromStr;

use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::RngExt;
use rand_distr::{Distribution, Normal};
use swarmpose_core::Correspondences;
use swarmpose_core::rng::seeded;

use crate::error::SimError;
use crate::scenario::{Geometry, SceneSpec};
use swarmpose_core::synthetic::random_unit;

/// How outliers are made.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OutlierMode {
    /// Wrong matches: `dst` replaced by a uniform box point.
    #[default]
    Random,
    /// A moving rigid object: a spatial cluster obeying another rigid motion.
    Structured,
}

impl OutlierMode {
    /// The name used in files and on the command line (`random`, `structured`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Self::Random => "random",
            Self::Structured => "structured",
        }
    }

    fn id(self) -> u64 {
        match self {
            Self::Random => 0,
            Self::Structured => 1,
        }
    }
}

impl fmt::Display for OutlierMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

impl FromStr for OutlierMode {
    type Err = SimError;

    fn from_str(s: &str) -> Result<Self, Self::Err> {
        match s {
            "random" => Ok(Self::Random),
            "structured" => Ok(Self::Structured),
            other => Err(SimError::InvalidConfig(format!(
                "unknown outlier mode {other:?} (expected random or structured)"
            ))),
        }
    }
}

/// One simulated problem and everything known about it.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// The correspondences, `dst ≈ R src + t` on inliers.
    pub data: Correspondences,
    /// The true camera motion.
    pub truth: Isometry3<f64>,
    /// `inlier[i]` is false where correspondence `i` is an outlier.
    pub inlier: Vec<bool>,
    /// Structured mode: the motion the outlier cluster obeys, `dst ≈ M src`.
    pub outlier_motion: Option<Isometry3<f64>>,
    /// Run seed (of the geometry).
    pub seed: u64,
    /// Noise σ per axis on `dst`, metres.
    pub noise_sigma: f64,
    /// Requested outlier fraction.
    pub outlier_fraction: f64,
    /// How outliers were made.
    pub mode: OutlierMode,
    /// Scene points drawn before the visibility test.
    pub n_drawn: usize,
}

impl Scenario {
    /// Number of outliers.
    #[must_use]
    pub fn n_outliers(&self) -> usize {
        self.inlier.iter().filter(|&&b| !b).count()
    }
}

/// SplitMix64 step: a well-mixed 64-bit value of `x`.
#[must_use]
pub fn splitmix(x: u64) -> u64 {
    let mut z = x.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^ (z >> 31)
}

/// Seed of the noise and outlier generator of (seed, noise, fraction, mode), like the
/// python's `default_rng([seed, noise*1e6, frac*1e6, mode, 7])`.
#[must_use]
pub fn corruption_seed(seed: u64, noise: f64, fraction: f64, mode: OutlierMode) -> u64 {
    let micro = |v: f64| (v * 1e6).round() as u64;
    [micro(noise), micro(fraction), mode.id(), 7]
        .iter()
        .fold(splitmix(seed), |h, &v| splitmix(h ^ v))
}

/// Checks a noise level and an outlier fraction.
///
/// # Errors
/// [`SimError::InvalidConfig`] for a negative or non-finite σ, or a fraction outside
/// `[0, 1)`.
pub fn check_levels(noise: f64, fraction: f64) -> Result<(), SimError> {
    if !(noise.is_finite() && noise >= 0.0) {
        return Err(SimError::InvalidConfig(format!(
            "noise level {noise} m: must be finite and >= 0"
        )));
    }
    if !(fraction.is_finite() && (0.0..1.0).contains(&fraction)) {
        return Err(SimError::InvalidConfig(format!(
            "outlier fraction {fraction}: must be in [0, 1)"
        )));
    }
    Ok(())
}

impl SceneSpec {
    /// The problem of run seed `seed` at noise σ (metres) and outlier fraction `fraction`.
    ///
    /// # Errors
    /// [`SimError::InvalidConfig`] for bad settings (see [`check_levels`]).
    pub fn scenario(
        &self,
        seed: u64,
        noise: f64,
        fraction: f64,
        mode: OutlierMode,
    ) -> Result<Scenario, SimError> {
        check_levels(noise, fraction)?;
        let geometry = self.geometry(seed)?;
        self.corrupt(&geometry, seed, noise, fraction, mode)
    }

    /// Noise and outliers on a given geometry (see the module documentation).
    ///
    /// # Errors
    /// As [`SceneSpec::scenario`].
    pub fn corrupt(
        &self,
        geometry: &Geometry,
        seed: u64,
        noise: f64,
        fraction: f64,
        mode: OutlierMode,
    ) -> Result<Scenario, SimError> {
        let Geometry {
            truth,
            points,
            n_drawn,
        } = geometry;
        check_levels(noise, fraction)?;
        let n = points.len();
        let mut rng = seeded(corruption_seed(seed, noise, fraction, mode));
        let mut src: Vec<Point3<f64>> = points
            .iter()
            .map(|p| truth.inverse_transform_point(p))
            .collect();
        let mut dst = points.clone();
        if noise > 0.0 {
            let normal =
                Normal::new(0.0, noise).map_err(|e| SimError::InvalidConfig(e.to_string()))?;
            for d in &mut dst {
                let jitter = Vector3::from_fn(|_, _| normal.sample(&mut rng));
                *d += jitter;
            }
        }
        let n_out = ((fraction * n as f64).round() as usize).min(n);
        let mut inlier = vec![true; n];
        let mut outlier_motion = None;
        if n_out > 0 {
            let idx: Vec<usize> = match mode {
                OutlierMode::Random => {
                    let idx = rand::seq::index::sample(&mut rng, n, n_out).into_vec();
                    for &i in &idx {
                        dst[i] = self.box_point(&mut rng);
                    }
                    idx
                }
                OutlierMode::Structured => {
                    let (idx, motion) = moving_object(points, n_out, &mut rng);
                    for &i in &idx {
                        src[i] = truth.inverse_transform_point(&(motion * points[i]));
                    }
                    // dst = X (+ noise) = M^-1 (R src + t) on the cluster.
                    outlier_motion = Some(motion.inverse() * truth);
                    idx
                }
            };
            for i in idx {
                inlier[i] = false;
            }
        }
        Ok(Scenario {
            data: Correspondences::new(src, dst)?,
            truth: *truth,
            inlier,
            outlier_motion,
            seed,
            noise_sigma: noise,
            outlier_fraction: fraction,
            mode,
            n_drawn: *n_drawn,
        })
    }
}

/// The `count` points nearest a random one, and the rigid motion `M` of that object
/// (camera-1 frame): `X' = R_m (X - c) + c + t_m` with `c` the cluster centroid.
fn moving_object(
    points: &[Point3<f64>],
    count: usize,
    rng: &mut swarmpose_core::SeededRng,
) -> (Vec<usize>, Isometry3<f64>) {
    let c0 = points[rng.random_range(0..points.len())];
    let mut order: Vec<usize> = (0..points.len()).collect();
    // Stable sort: ties keep index order, as numpy's argsort(kind="stable").
    order.sort_by(|&a, &b| (points[a] - c0).norm().total_cmp(&(points[b] - c0).norm()));
    order.truncate(count);
    let c = order
        .iter()
        .map(|&i| points[i].coords)
        .sum::<Vector3<f64>>()
        / count as f64;
    let angle = rng.random_range(5.0f64..20.0).to_radians();
    let rm = UnitQuaternion::from_axis_angle(&random_unit(rng), angle);
    let tm = random_unit(rng).into_inner() * rng.random_range(0.5..2.0);
    let motion = Isometry3::from_parts(Translation3::from(c + tm - rm * c), rm);
    (order, motion)
}
