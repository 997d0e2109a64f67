//! A vehicle in front of the camera, for [`super::features::FeatureSequence`]: the back
//! of a truck that drives in the camera's lane, covering the landmarks behind it. When
//! it keeps the camera's speed its features stand still in the images, and when it
//! fills enough of the view it holds more matches than the static world: the classic
//! case where an odometry says "standing still" with confidence.

use nalgebra::Point3;
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use swarmpose_vision::stereo::RectifiedStereo;

/// Half the width of the vehicle's back, metres.
const HALF_WIDTH_M: f64 = 1.25;
/// Top and bottom of its back in the camera frame (y down; the camera 1.65 m above the
/// road), metres.
const TOP_M: f64 = -1.8;
const BOTTOM_M: f64 = 1.4;

/// A vehicle driving ahead of the camera in its lane.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Vehicle {
    /// First and last frame (inclusive) in which it is seen.
    pub frames: (usize, usize),
    /// Features on its back.
    pub features: usize,
    /// Its distance ahead of the camera in its first frame, metres.
    pub distance_m: f64,
    /// How much its distance grows per frame, metres (0: it keeps the camera's speed,
    /// and its features stand still in the images).
    pub relative_step_m: f64,
}

/// One feature of the vehicle in the camera frame of one frame.
pub(crate) struct VehicleFeature {
    /// Position in the left camera frame, metres.
    pub camera: Point3<f64>,
    /// Descriptor (the same in every frame before the measurement's bit noise).
    pub descriptor: [u8; 32],
}

impl Vehicle {
    /// True when it is seen in frame `k`.
    #[must_use]
    pub fn seen_in(&self, k: usize) -> bool {
        (self.frames.0..=self.frames.1).contains(&k)
    }

    /// Its distance ahead of the camera in frame `k`, metres.
    fn distance_m(&self, k: usize) -> f64 {
        self.distance_m + self.relative_step_m * (k as f64 - self.frames.0 as f64)
    }

    /// Its features in the camera frame of frame `k` (none when it is not seen),
    /// generated from `seed`: the same features in every frame.
    pub(crate) fn features(&self, k: usize, seed: u64) -> Vec<VehicleFeature> {
        if !self.seen_in(k) {
            return Vec::new();
        }
        let z = self.distance_m(k);
        let mut rng = ChaCha8Rng::seed_from_u64(seed ^ 0x7275_636B_5F62_6163);
        (0..self.features)
            .map(|_| {
                let x = rng.random_range(-HALF_WIDTH_M..HALF_WIDTH_M);
                let y = rng.random_range(TOP_M..BOTTOM_M);
                let mut descriptor = [0u8; 32];
                rng.fill(&mut descriptor[..]);
                VehicleFeature {
                    camera: Point3::new(x, y, z),
                    descriptor,
                }
            })
            .collect()
    }

    /// True when the vehicle hides the point `p` (left camera frame of frame `k`): it
    /// lies behind the vehicle's back, within its outline in the left image.
    pub(crate) fn hides(&self, k: usize, rig: &RectifiedStereo, p: &Point3<f64>) -> bool {
        if !self.seen_in(k) {
            return false;
        }
        let z = self.distance_m(k);
        if p.z <= z {
            return false;
        }
        let (u, v) = rig.project_left(p);
        let (u0, v0) = rig.project_left(&Point3::new(-HALF_WIDTH_M, TOP_M, z));
        let (u1, v1) = rig.project_left(&Point3::new(HALF_WIDTH_M, BOTTOM_M, z));
        (u0..=u1).contains(&u) && (v0..=v1).contains(&v)
    }
}
