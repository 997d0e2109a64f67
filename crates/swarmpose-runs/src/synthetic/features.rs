//! A synthetic stream of triangulated stereo features, generated on the fly: a street of
//! landmarks along a gently curving path, measured by a stereo camera with known pixel
//! noise, wrong matches, clutter and, optionally, a right camera that is not the
//! calibrated one. No images: the frames go straight to the back end
//! ([`swarmpose_odometry::tracker::Tracker`]), so thousands of frames take seconds, with every
//! quantity known (for the covariance's honesty, the self-calibration's decisions and the
//! memory of long runs).
//!
//! Landmarks are generated per 2 m cell of the path from a seed and the cell's index, so
//! the world is the same each time it is visited and nothing is stored between frames.

use nalgebra::{Isometry3, Matrix3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, StandardNormal};
use swarmpose_vision::features::{BinaryDescriptor, Keypoint};
use swarmpose_vision::frontend::StereoFrame;
use swarmpose_vision::stereo::RectifiedStereo;

use swarmpose_odometry::OdometryConfig;
use swarmpose_odometry::StereoCamera;
use swarmpose_odometry::refine::model::PixelNoise;
use swarmpose_odometry::tracker::Tracker;

use super::vehicle::Vehicle;

/// Length of a path segment of constant curvature, metres.
const SEGMENT_M: f64 = 80.0;
/// Length of a landmark cell along the path, metres.
const CELL_M: f64 = 2.0;

/// Landmarks are generated this far ahead of the camera, metres.
const AHEAD_M: f64 = 70.0;
/// Bits flipped in a landmark's descriptor at each observation.
const DESCRIPTOR_NOISE_BITS: usize = 12;

/// Settings of a [`FeatureSequence`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureSequenceConfig {
    /// The calibrated rig (KITTI-like by default).
    pub rig: RectifiedStereo,
    /// Image size, pixels.
    pub size: (usize, usize),
    /// Pixel noise of the measurements.
    pub noise: PixelNoise,
    /// Metres forward per frame (default 1.0).
    pub step_m: f64,
    /// Seconds per frame (default 0.1).
    pub frame_period_s: f64,
    /// Yaw per frame in the turns, radians: the path alternates 80 m straight, 80 m
    /// turning left, 80 m straight, 80 m turning right (default 0.02).
    pub max_yaw_rad: f64,
    /// Share of the observations matched to another landmark's descriptor (default 0.1).
    pub mismatch_share: f64,
    /// Features per frame that are no landmark (default 50).
    pub clutter: usize,
    /// Principal point column of the right camera minus the calibration's, pixels:
    /// measured disparities are short by this much (default 0).
    pub principal_point_px: f64,
    /// `f ψ` of a yaw `ψ` of the right camera, pixels: disparities short by
    /// `−f ψ (1 + x²)` and rows offset by `−f ψ x y` (default 0).
    pub f_yaw_px: f64,
    /// Landmarks per 2 m of path (default 40).
    pub landmarks_per_cell: usize,
    /// Seed of the world and of the noise (default 0).
    pub seed: u64,
    /// A vehicle driving ahead in the camera's lane (default none).
    pub vehicle: Option<Vehicle>,
}

impl Default for FeatureSequenceConfig {
    fn default() -> Self {
        Self {
            rig: RectifiedStereo {
                fx: 718.856,
                fy: 718.856,
                cx: 607.19,
                cy: 185.22,
                baseline_m: 0.537,
            },
            size: (1241, 376),
            noise: PixelNoise {
                position_px: 0.5,
                disparity_px: 0.25,
            },
            step_m: 1.0,
            frame_period_s: 0.1,
            max_yaw_rad: 0.02,
            mismatch_share: 0.1,
            clutter: 50,
            principal_point_px: 0.0,
            f_yaw_px: 0.0,
            landmarks_per_cell: 40,
            seed: 0,
            vehicle: None,
        }
    }
}

/// A synthetic feature stream (see the module documentation).
#[derive(Debug, Clone)]
pub struct FeatureSequence {
    config: FeatureSequenceConfig,
}

/// One landmark: its position in the world and its descriptor.
struct Landmark {
    world: Point3<f64>,
    descriptor: [u8; 32],
}

impl FeatureSequence {
    /// A stream with these settings.
    #[must_use]
    pub fn new(config: FeatureSequenceConfig) -> Self {
        Self { config }
    }

    /// The settings.
    #[must_use]
    pub fn config(&self) -> &FeatureSequenceConfig {
        &self.config
    }

    /// A back end for this stream: its camera and pixel noise, the ORB front end's
    /// matching, the default robust estimator.
    #[must_use]
    pub fn tracker(&self, config: OdometryConfig) -> Tracker<BinaryDescriptor> {
        let c = &self.config;
        let camera = StereoCamera {
            rig: c.rig,
            width: c.size.0,
            height: c.size.1,
        };
        let temporal = swarmpose_vision::frontend::Frontend::orb(c.rig).temporal;
        let estimator = Box::new(swarmpose_core::PsoEstimator::new(
            swarmpose_core::PsoEstimatorConfig::default(),
        ));
        Tracker::new(camera, c.noise, temporal, config, estimator)
    }

    /// Curvature of path segment `i` (1/m): straight, left turn, straight, right turn.
    fn curvature(&self, i: u64) -> f64 {
        let c = &self.config;
        let kappa = c.max_yaw_rad / c.step_m;
        match i % 4 {
            1 => kappa,
            3 => -kappa,
            _ => 0.0,
        }
    }

    /// Heading (radians, about y: positive turns right) and position (x right, z
    /// forward, metres) after `s` metres along the path: segments of [`SEGMENT_M`] of
    /// constant curvature, summed in closed form.
    fn along(&self, s: f64) -> (f64, Point3<f64>) {
        let s = s.max(0.0);
        let (mut heading, mut x, mut z) = (0.0f64, 0.0f64, 0.0f64);
        let mut i = 0u64;
        let mut left = s;
        loop {
            let len = left.min(SEGMENT_M);
            let c = self.curvature(i);
            if c == 0.0 {
                x += len * heading.sin();
                z += len * heading.cos();
            } else {
                let end = heading + c * len;
                x += (heading.cos() - end.cos()) / c;
                z += (end.sin() - heading.sin()) / c;
                heading = end;
            }
            left -= len;
            i += 1;
            if left <= 0.0 {
                return (heading, Point3::new(x, 0.0, z));
            }
        }
    }

    /// The true pose of the left camera at frame `k` in the frame of camera 0.
    #[must_use]
    pub fn pose(&self, k: usize) -> Isometry3<f64> {
        let (heading, p) = self.along(k as f64 * self.config.step_m);
        Isometry3::from_parts(
            Translation3::from(p.coords),
            UnitQuaternion::from_axis_angle(&Vector3::y_axis(), heading),
        )
    }

    /// Timestamp of frame `k`, seconds.
    #[must_use]
    pub fn timestamp_s(&self, k: usize) -> f64 {
        k as f64 * self.config.frame_period_s
    }

    /// The landmarks of cell `i` (deterministic).
    fn cell(&self, i: i64) -> Vec<Landmark> {
        let mut rng = ChaCha8Rng::seed_from_u64(
            self.config.seed ^ (i as u64).wrapping_mul(0x9E37_79B9_7F4A_7C15),
        );
        let s0 = i as f64 * CELL_M;
        (0..self.config.landmarks_per_cell)
            .map(|_| {
                let s = s0 + rng.random_range(0.0..CELL_M);
                let (heading, at) = self.along(s);
                let frame = Isometry3::from_parts(
                    Translation3::from(at.coords),
                    UnitQuaternion::from_axis_angle(&Vector3::y_axis(), heading),
                );
                // Ground, two house fronts, and things up to 60 m to the sides.
                let local = match rng.random_range(0..4) {
                    0 => Point3::new(rng.random_range(-8.0..8.0), 1.65, 0.0),
                    1 => Point3::new(-7.0, rng.random_range(-6.0..1.6), 0.0),
                    2 => Point3::new(8.0, rng.random_range(-6.0..1.6), 0.0),
                    _ => Point3::new(
                        rng.random_range(-60.0..60.0),
                        rng.random_range(-10.0..1.6),
                        0.0,
                    ),
                };
                let mut descriptor = [0u8; 32];
                rng.fill(&mut descriptor[..]);
                Landmark {
                    world: frame * local,
                    descriptor,
                }
            })
            .collect()
    }

    /// The triangulated features of frame `k`, as the front end would give them.
    #[must_use]
    pub fn frame(&self, k: usize) -> StereoFrame<BinaryDescriptor> {
        let c = &self.config;
        let rig = &c.rig;
        let mut rng = ChaCha8Rng::seed_from_u64(c.seed.wrapping_add(1_000_003 * (k as u64 + 1)));
        let pose_inv = self.pose(k).inverse();
        let s = k as f64 * c.step_m;
        let first = ((s - 10.0) / CELL_M).floor() as i64;
        let last = ((s + AHEAD_M) / CELL_M).ceil() as i64;
        let landmarks: Vec<Landmark> = (first..=last).flat_map(|i| self.cell(i)).collect();
        let mut out = StereoFrame::default();
        let (w, h) = (c.size.0 as f64, c.size.1 as f64);
        let fb = rig.fx * rig.baseline_m;
        // A measurement `(u, v, d, row offset)` of a point of the left camera frame, if
        // it is seen.
        let measure = |rng: &mut ChaCha8Rng, p: &Point3<f64>| -> Option<[f64; 4]> {
            if p.z < 2.0 || p.z > 100.0 {
                return None;
            }
            let (u, v) = rig.project_left(p);
            if !(4.0..w - 4.0).contains(&u) || !(4.0..h - 4.0).contains(&v) {
                return None;
            }
            // The right camera's errors, on its normalised coordinates.
            let xr = (p.x - rig.baseline_m) / p.z;
            let yn = p.y / p.z;
            let delta = c.principal_point_px - c.f_yaw_px * (1.0 + xr * xr);
            let d = fb / p.z - delta + gauss(rng, c.noise.disparity_px);
            if d < 0.5 {
                return None;
            }
            let row = -c.f_yaw_px * xr * yn + gauss(rng, c.noise.disparity_px);
            Some([
                u + gauss(rng, c.noise.position_px),
                v + gauss(rng, c.noise.position_px),
                d,
                row,
            ])
        };
        for (j, l) in landmarks.iter().enumerate() {
            let p = pose_inv * l.world;
            if c.vehicle.is_some_and(|car| car.hides(k, rig, &p)) {
                continue;
            }
            let Some([u, v, d, row]) = measure(&mut rng, &p) else {
                continue;
            };
            let mut descriptor = if rng.random_bool(c.mismatch_share) {
                landmarks
                    [(j + 1 + rng.random_range(0..landmarks.len().max(2) - 1)) % landmarks.len()]
                .descriptor
            } else {
                l.descriptor
            };
            for _ in 0..DESCRIPTOR_NOISE_BITS {
                let bit = rng.random_range(0..256usize);
                descriptor[bit / 8] ^= 1 << (bit % 8);
            }
            push(&mut out, rig, u, v, d, row, descriptor, &c.noise);
        }
        if let Some(car) = &c.vehicle {
            for f in car.features(k, c.seed) {
                let Some([u, v, d, row]) = measure(&mut rng, &f.camera) else {
                    continue;
                };
                let mut descriptor = f.descriptor;
                for _ in 0..DESCRIPTOR_NOISE_BITS {
                    let bit = rng.random_range(0..256usize);
                    descriptor[bit / 8] ^= 1 << (bit % 8);
                }
                push(&mut out, rig, u, v, d, row, descriptor, &c.noise);
            }
        }
        for _ in 0..c.clutter {
            let u = rng.random_range(4.0..w - 4.0);
            let v = rng.random_range(4.0..h - 4.0);
            let d = rng.random_range(1.0..60.0);
            let mut descriptor = [0u8; 32];
            rng.fill(&mut descriptor[..]);
            push(&mut out, rig, u, v, d, 0.0, descriptor, &c.noise);
        }
        out.n_left_features = out.len();
        out.n_right_features = out.len();
        out
    }
}

/// A normal sample of standard deviation `sigma`.
fn gauss(rng: &mut ChaCha8Rng, sigma: f64) -> f64 {
    let z: f64 = StandardNormal.sample(rng);
    sigma * z
}

/// Appends one measured feature to `out`.
#[allow(clippy::too_many_arguments)]
fn push(
    out: &mut StereoFrame<BinaryDescriptor>,
    rig: &RectifiedStereo,
    u: f64,
    v: f64,
    d: f64,
    row: f64,
    descriptor: [u8; 32],
    noise: &PixelNoise,
) {
    let Some(point) = rig.triangulate(u, v, d) else {
        return;
    };
    let kp = |x: f64, y: f64| Keypoint {
        x: x as f32,
        y: y as f32,
        scale: 7.0,
        angle: 0.0,
        response: 1.0,
        octave: 0,
    };
    out.left_keypoints.push(kp(u, v));
    out.right_keypoints.push(kp(u - d, v + row));
    out.left_descriptors.push(BinaryDescriptor(descriptor));
    out.right_descriptors.push(BinaryDescriptor(descriptor));
    out.points.push(point);
    out.disparities_px.push(d as f32);
    out.row_offsets_px.push(row as f32);
    out.sigmas_m
        .push(rig.point_sigma(point.z, noise.disparity_px, noise.position_px));
    let cov: Matrix3<f64> = rig.point_covariance(u, v, d, noise.position_px, noise.disparity_px);
    out.covariances.push(cov);
}
