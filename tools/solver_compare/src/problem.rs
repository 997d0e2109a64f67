//! The synthetic window: a KITTI-like rig driving forward and turning slightly over ten
//! keyframes, about 2 000 tracks of 2-10 consecutive keyframes, noisy stereo measurements
//! with a few per cent of gross outliers, and the drifting initial poses a chain of pair
//! motions would give. Every random choice comes from one seeded generator.

use nalgebra::{Isometry3, Matrix3, Point3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use swarmpose_odometry::refine::model::{PixelNoise, StereoModel, StereoObservation};
use swarmpose_vision::frontend::DisparityCorrection;
use swarmpose_vision::stereo::RectifiedStereo;

/// Keyframes in the window (the engine's default on KITTI).
pub const KEYFRAMES: usize = 10;
/// Huber threshold on a measurement's whitened residual norm (the engine's default).
pub const HUBER_K: f64 = 2.5;
/// Image size, pixels (KITTI sequence 00).
const WIDTH: f64 = 1241.0;
const HEIGHT: f64 = 376.0;

/// How the problem is drawn.
#[derive(Debug, Clone, Copy)]
pub struct Spec {
    pub seed: u64,
    pub tracks: usize,
    /// Fraction of measurements replaced by gross outliers.
    pub outliers: f64,
}

/// One track: the keyframe of its first measurement (its anchor) and one measurement
/// per consecutive keyframe from there.
#[derive(Debug, Clone)]
pub struct Track {
    pub first: usize,
    pub obs: Vec<StereoObservation>,
}

/// The window problem.
#[derive(Debug, Clone)]
pub struct Problem {
    pub model: StereoModel,
    /// True poses, the camera in the world (`T_wk`); keyframe 0 is the world.
    pub truth: Vec<Isometry3<f64>>,
    /// Initial poses, the camera in the world: keyframe 0 exact (it is held fixed), the
    /// others the chain of pair motions with their errors.
    pub initial: Vec<Isometry3<f64>>,
    pub tracks: Vec<Track>,
    /// Measurements replaced by outliers.
    pub outliers: usize,
}

/// The KITTI rig of sequence 00 (left grey camera), with the engine's pixel noise and no
/// disparity correction.
pub fn kitti_model() -> StereoModel {
    StereoModel {
        rig: RectifiedStereo {
            fx: 718.856,
            fy: 718.856,
            cx: 607.1928,
            cy: 185.2157,
            baseline_m: 0.537,
        },
        noise: PixelNoise {
            position_px: 0.5,
            disparity_px: 0.25,
        },
        correction: DisparityCorrection::default(),
    }
}

/// The exact measurement of the world point `pw` from the camera at `pose` (`T_wk`), if
/// it is in the image and at least 2 m in front.
fn measure(m: &StereoModel, pose: &Isometry3<f64>, pw: &Point3<f64>) -> Option<StereoObservation> {
    let p = pose.inverse_transform_point(pw);
    if p.z < 2.0 {
        return None;
    }
    let r = &m.rig;
    let (u, v) = (r.fx * p.x / p.z + r.cx, r.fy * p.y / p.z + r.cy);
    (u > 5.0 && u < WIDTH - 5.0 && v > 5.0 && v < HEIGHT - 5.0).then_some(StereoObservation {
        u,
        v,
        d: r.fx * r.baseline_m / p.z,
    })
}

/// A small random rigid motion: translation `N(0, sigma_t)` per axis (metres), rotation
/// `N(0, sigma_r)` per axis (radians).
fn jitter(rng: &mut ChaCha8Rng, sigma_t: f64, sigma_r: f64) -> Isometry3<f64> {
    let mut n = |s: f64| Normal::new(0.0, s).map_or(0.0, |d| d.sample(rng));
    let t = Vector3::new(n(sigma_t), n(sigma_t), n(sigma_t));
    let r = Vector3::new(n(sigma_r), n(sigma_r), n(sigma_r));
    Isometry3::from_parts(Translation3::from(t), UnitQuaternion::from_scaled_axis(r))
}

/// Track length: 2 + a geometric number with ratio 0.7, at most 10 (mean about 4).
fn track_length(rng: &mut ChaCha8Rng) -> usize {
    let mut len = 2;
    while len < KEYFRAMES && rng.random_range(0.0..1.0) < 0.7 {
        len += 1;
    }
    len
}

impl Problem {
    /// Draws the problem of `spec`.
    pub fn generate(spec: &Spec) -> Self {
        let model = kitti_model();
        let mut rng = ChaCha8Rng::seed_from_u64(spec.seed);
        // The path: about 1 m forward a keyframe, turning 0.5-1.5 degrees about the
        // vertical, with a little pitch and sideways motion.
        let mut truth = vec![Isometry3::identity()];
        let mut initial = vec![Isometry3::identity()];
        for _ in 1..KEYFRAMES {
            let step = Isometry3::from_parts(
                Translation3::new(
                    rng.random_range(-0.03..0.03),
                    rng.random_range(-0.02..0.02),
                    rng.random_range(0.9..1.1),
                ),
                UnitQuaternion::from_euler_angles(
                    rng.random_range(-0.2f64..0.2).to_radians(),
                    rng.random_range(0.5f64..1.5).to_radians(),
                    0.0,
                ),
            );
            // The pair's measurement of the step: 2 cm and 0.1 degree per axis.
            let error = jitter(&mut rng, 0.02, 0.1f64.to_radians());
            let (t, g) = (truth[truth.len() - 1], initial[initial.len() - 1]);
            truth.push(t * step);
            initial.push(g * step * error);
        }
        let pos = Normal::new(0.0, model.noise.position_px).ok();
        let disp = Normal::new(0.0, model.noise.disparity_px).ok();
        let mut tracks = Vec::with_capacity(spec.tracks);
        let mut outliers = 0;
        while tracks.len() < spec.tracks {
            let len = track_length(&mut rng);
            let first = rng.random_range(0..=KEYFRAMES - len);
            // A point seen from its first keyframe anywhere in the image, 5-60 m away.
            let (u, v) = (
                rng.random_range(20.0..WIDTH - 20.0),
                rng.random_range(20.0..HEIGHT - 20.0),
            );
            let z = rng.random_range(5.0..60.0);
            let r = &model.rig;
            let pc = Point3::new((u - r.cx) * z / r.fx, (v - r.cy) * z / r.fy, z);
            let pw = truth[first] * pc;
            let exact: Option<Vec<StereoObservation>> = (first..first + len)
                .map(|k| measure(&model, &truth[k], &pw))
                .collect();
            let Some(exact) = exact else { continue };
            let obs = exact
                .into_iter()
                .map(|z| {
                    if rng.random_range(0.0..1.0) < spec.outliers {
                        outliers += 1;
                        let sign = |rng: &mut ChaCha8Rng| {
                            if rng.random_range(0.0..1.0) < 0.5 {
                                -1.0
                            } else {
                                1.0
                            }
                        };
                        StereoObservation {
                            u: z.u + sign(&mut rng) * rng.random_range(5.0..30.0),
                            v: z.v + sign(&mut rng) * rng.random_range(5.0..30.0),
                            d: (z.d + sign(&mut rng) * rng.random_range(1.0..5.0)).max(1.0),
                        }
                    } else {
                        let mut n = |d: &Option<Normal<f64>>| d.map_or(0.0, |d| d.sample(&mut rng));
                        StereoObservation {
                            u: z.u + n(&pos),
                            v: z.v + n(&pos),
                            d: (z.d + n(&disp)).max(0.5),
                        }
                    }
                })
                .collect();
            tracks.push(Track { first, obs });
        }
        Self {
            model,
            truth,
            initial,
            tracks,
            outliers,
        }
    }

    /// Stereo measurements in the window.
    pub fn observations(&self) -> usize {
        self.tracks.iter().map(|t| t.obs.len()).sum()
    }

    /// The initial point of every track: its anchor measurement inverted,
    /// `(x, y, ρ)` in its first keyframe (what swarmpose's window starts from, too).
    pub fn initial_points(&self) -> Vec<Vector3<f64>> {
        self.tracks
            .iter()
            .map(|t| self.model.anchor(&t.obs[0]))
            .collect()
    }
}

/// A pose `T_kw` (world to camera) as rotation matrix and translation.
pub type PoseCw = (Matrix3<f64>, Vector3<f64>);

/// `T_kw` of a camera-in-world pose.
pub fn pose_cw(pose_wc: &Isometry3<f64>) -> PoseCw {
    let t = pose_wc.inverse();
    (
        *t.rotation.to_rotation_matrix().matrix(),
        t.translation.vector,
    )
}

/// The camera-in-world pose of a `T_kw` (the rotation converted exactly, not by
/// nalgebra's iterative `from_matrix`).
pub fn pose_wc((rot, trans): &PoseCw) -> Isometry3<f64> {
    let q = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(*rot));
    Isometry3::from_parts(Translation3::from(*trans), q).inverse()
}

/// Huber cost of a squared whitened norm (the engine's `ρ`).
fn huber(s2: f64, k: f64) -> f64 {
    if s2 <= k * k {
        s2
    } else {
        2.0 * k * s2.sqrt() - k * k
    }
}

/// The robust cost `Σ ρ(‖e‖²)` of the problem at the poses `T_kw` and points `(x, y, ρ)`
/// (each in its track's first keyframe), with swarmpose's own measurement model; infinity
/// when a point is behind a camera that sees it.
pub fn robust_cost(p: &Problem, poses: &[PoseCw], points: &[Vector3<f64>]) -> f64 {
    let mut total = 0.0;
    for (t, x) in p.tracks.iter().zip(points) {
        let (ra, ta) = &poses[t.first];
        for (i, z) in t.obs.iter().enumerate() {
            let r2 = if i == 0 {
                p.model.residual2_in_reference(x, z)
            } else {
                let (rj, tj) = &poses[t.first + i];
                let rot = rj * ra.transpose();
                let trans = tj - rot * ta;
                match p.model.residual2_in_current(&rot, &trans, x, z) {
                    Some(r2) => r2,
                    None => return f64::INFINITY,
                }
            };
            total += huber(r2, HUBER_K);
        }
    }
    total
}

/// Translation (metres) and rotation (degrees) error of an estimated camera-in-world pose.
pub fn pose_error(truth: &Isometry3<f64>, estimate: &Isometry3<f64>) -> (f64, f64) {
    let dt = (truth.translation.vector - estimate.translation.vector).norm();
    let dr = (truth.rotation.inverse() * estimate.rotation)
        .angle()
        .to_degrees();
    (dt, dr)
}
