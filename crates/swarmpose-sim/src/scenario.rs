//! The section-6 scene: points in a box seen by two cameras, following the geometry of
//! `gen_scenarios.py`.
//!
//! Camera 1 is the identity; camera 2 sits at a random pose `(R, t)` in camera 1's frame
//! (rotation angle uniform in `[0, 20°]` about a uniform axis, translation length uniform
//! in `[0, 1.5]` m in a uniform direction). Scene points are uniform in the box
//! `x, y ∈ [-6, 6]`, `z ∈ [2, 25]` m (camera-1 frame) and only those visible in both images
//! ([`Pinhole::sees`]) are kept. `src` is a point in camera 2's frame, `dst` the same point
//! in camera 1's frame, so `dst = R src + t`.
//!
//! The geometry depends on the run seed only, so a run index gives the same scene and
//! camera pose at every noise level and outlier fraction (paired comparisons); noise and
//! outliers come from a second generator seeded by (seed, noise, fraction, mode), see
//! [`crate::outliers`].

use nalgebra::{Isometry3, Point3};
use rand::RngExt;
use swarmpose_core::SeededRng;
use swarmpose_core::rng::seeded;
use swarmpose_core::synthetic::random_motion;

use crate::camera::Pinhole;
use crate::error::SimError;

/// Least number of visible points a scene is drawn until (more batches are drawn below).
pub const MIN_VISIBLE: usize = 10;

/// Most batches of scene points drawn before giving up on a setting that sees nothing.
const MAX_BATCHES: usize = 10_000;

/// How the scene and camera 2 are drawn. Defaults in brackets (those of `gen_scenarios.py`).
#[derive(Debug, Clone, PartialEq)]
pub struct SceneSpec {
    /// Scene points drawn per batch \[400\].
    pub n_scene: usize,
    /// Draw batches until at least this many points are visible, then keep exactly this
    /// many [`None`: one batch, keep every visible point].
    pub n_target: Option<usize>,
    /// Lower corner of the scene box, camera-1 frame, metres [(-6, -6, 2)].
    pub box_lo: [f64; 3],
    /// Upper corner of the scene box, metres [(6, 6, 25)].
    pub box_hi: [f64; 3],
    /// Largest rotation of camera 2, degrees \[20\].
    pub max_rotation_deg: f64,
    /// Largest translation of camera 2, metres [1.5].
    pub max_translation_m: f64,
    /// Both cameras' intrinsics [`Pinhole::default`].
    pub camera: Pinhole,
}

impl Default for SceneSpec {
    fn default() -> Self {
        Self {
            n_scene: 400,
            n_target: None,
            box_lo: [-6.0, -6.0, 2.0],
            box_hi: [6.0, 6.0, 25.0],
            max_rotation_deg: 20.0,
            max_translation_m: 1.5,
            camera: Pinhole::default(),
        }
    }
}

/// The scene of one run: the camera motion and the points both cameras see.
#[derive(Debug, Clone, PartialEq)]
pub struct Geometry {
    /// The true motion, `dst = R src + t` (camera 2 frame to camera 1 frame).
    pub truth: Isometry3<f64>,
    /// Visible scene points in camera 1's frame (noise-free `dst`), metres.
    pub points: Vec<Point3<f64>>,
    /// Scene points drawn before the visibility test.
    pub n_drawn: usize,
}

impl SceneSpec {
    /// Checks the settings.
    ///
    /// # Errors
    /// [`SimError::InvalidConfig`] for an empty batch, an empty box or negative motion
    /// limits.
    pub fn validate(&self) -> Result<(), SimError> {
        if self.n_scene == 0 {
            return Err(SimError::InvalidConfig("n_scene must be at least 1".into()));
        }
        if self.n_target.is_some_and(|n| n < MIN_VISIBLE) {
            return Err(SimError::InvalidConfig(format!(
                "n_target must be at least {MIN_VISIBLE}"
            )));
        }
        if (0..3)
            .any(|k| self.box_lo[k].partial_cmp(&self.box_hi[k]) != Some(std::cmp::Ordering::Less))
        {
            return Err(SimError::InvalidConfig("box must have lo < hi".into()));
        }
        let limits = [self.max_rotation_deg, self.max_translation_m];
        if limits.iter().any(|v| !(v.is_finite() && *v >= 0.0)) {
            return Err(SimError::InvalidConfig(
                "motion limits must be finite and >= 0".into(),
            ));
        }
        Ok(())
    }

    /// A uniform point of the scene box.
    pub(crate) fn box_point(&self, rng: &mut SeededRng) -> Point3<f64> {
        Point3::new(
            rng.random_range(self.box_lo[0]..self.box_hi[0]),
            rng.random_range(self.box_lo[1]..self.box_hi[1]),
            rng.random_range(self.box_lo[2]..self.box_hi[2]),
        )
    }

    /// The scene and camera-2 pose of `seed` (they depend on nothing else).
    ///
    /// # Errors
    /// [`SimError::InvalidConfig`] for bad settings, or when [`MIN_VISIBLE`] points are
    /// not seen after many batches.
    pub fn geometry(&self, seed: u64) -> Result<Geometry, SimError> {
        self.validate()?;
        let mut rng = seeded(seed);
        let angle = rng.random_range(0.0..=self.max_rotation_deg).to_radians();
        let truth = random_motion(&mut rng, angle, self.max_translation_m);
        let wanted = self.n_target.unwrap_or(MIN_VISIBLE).max(MIN_VISIBLE);
        let mut points = Vec::new();
        let mut n_drawn = 0;
        for _ in 0..MAX_BATCHES {
            for _ in 0..self.n_scene {
                let x1 = self.box_point(&mut rng);
                if self.camera.sees(&x1) && self.camera.sees(&truth.inverse_transform_point(&x1)) {
                    points.push(x1);
                }
            }
            n_drawn += self.n_scene;
            if points.len() >= wanted {
                if let Some(n) = self.n_target {
                    points.truncate(n);
                }
                return Ok(Geometry {
                    truth,
                    points,
                    n_drawn,
                });
            }
        }
        Err(SimError::InvalidConfig(format!(
            "fewer than {wanted} scene points visible in both cameras after {n_drawn} draws"
        )))
    }
}
