use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;

use super::*;

pub(super) fn model() -> StereoModel {
    crate::refine::model::test_model(Default::default())
}

/// The measurement of the world point `pw` by the camera at `pose` (camera in world), if
/// it is in view.
pub(super) fn measure(
    m: &StereoModel,
    pose: &Isometry3<f64>,
    pw: &Point3<f64>,
) -> Option<StereoObservation> {
    let p = pose.inverse() * pw;
    if p.z < 1.0 {
        return None;
    }
    let r = &m.rig;
    let (u, v) = (r.fx * p.x / p.z + r.cx, r.fy * p.y / p.z + r.cy);
    (u > 0.0 && u < 1240.0 && v > 0.0 && v < 370.0).then_some(StereoObservation {
        u,
        v,
        d: r.fx * r.baseline_m / p.z,
    })
}

/// `n` random points (seed `seed`), metres: `x` within `±half_width_m`, `y` in [-3, 2)
/// (y down), `z` in [4, `max_depth_m`).
pub(super) fn random_points(
    seed: u64,
    n: usize,
    half_width_m: f64,
    max_depth_m: f64,
) -> Vec<Point3<f64>> {
    random_points_from(
        &mut ChaCha8Rng::seed_from_u64(seed),
        n,
        half_width_m,
        max_depth_m,
    )
}

/// [`random_points`] drawn from `rng`.
fn random_points_from(
    rng: &mut ChaCha8Rng,
    n: usize,
    half_width_m: f64,
    max_depth_m: f64,
) -> Vec<Point3<f64>> {
    (0..n)
        .map(|_| {
            Point3::new(
                rng.random_range(-half_width_m..half_width_m),
                rng.random_range(-3.0..2.0),
                rng.random_range(4.0..max_depth_m),
            )
        })
        .collect()
}

/// The error the window is given on each frame's pose: 1 cm sideways, 0.05 degree of yaw.
fn drift_error() -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(0.01, 0.0, 0.0),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 0.05f64.to_radians()),
    )
}

/// A camera driving forward 1 m a frame and turning 1 degree, among 300 random points;
/// the window is given poses that drift by 1 cm and 0.05 degree a frame.
fn drive(keyframes: usize, frames: usize) -> (Vec<Isometry3<f64>>, Vec<Isometry3<f64>>) {
    let config = WindowConfig {
        keyframes,
        max_iterations: 20,
        ..WindowConfig::default()
    };
    drive_with(config, frames, None)
}

/// [`drive`] with the window's `config`, and with `noise` (seed, pixels: uniform within
/// ± that on the positions, half on the disparities) on the measurements.
pub(super) fn drive_with(
    config: WindowConfig,
    frames: usize,
    noise: Option<(u64, f64)>,
) -> (Vec<Isometry3<f64>>, Vec<Isometry3<f64>>) {
    let keyframes = config.keyframes;
    let mut rng = ChaCha8Rng::seed_from_u64(noise.map_or(0, |n| n.0));
    let px = noise.map_or(0.0, |n| n.1);
    let mut noisy = |z: StereoObservation| {
        if px == 0.0 {
            return z;
        }
        StereoObservation {
            u: z.u + rng.random_range(-px..px),
            v: z.v + rng.random_range(-px..px),
            d: z.d + rng.random_range(-px / 2.0..px / 2.0),
        }
    };
    let m = model();
    let points = random_points(7, 300, 15.0, 40.0);
    let step = Isometry3::from_parts(
        Translation3::new(0.0, 0.0, 1.0),
        UnitQuaternion::from_axis_angle(&Vector3::y_axis(), 1f64.to_radians()),
    );
    let error = drift_error();
    let mut window = Window::new(config);
    let (mut truth, mut given) = (vec![Isometry3::identity()], vec![Isometry3::identity()]);
    for i in 1..frames {
        let t_prev = truth[i - 1];
        let t = t_prev * step;
        let links: Vec<Link> = points
            .iter()
            .enumerate()
            // Each point is seen in 4 consecutive frames out of every 6.
            .filter(|(k, _)| (i + k) % 6 < 4)
            .filter_map(|(k, pw)| {
                let current = noisy(measure(&m, &t, pw)?);
                Some(Link {
                    reference_feature: k,
                    current_feature: k,
                    reference: noisy(measure(&m, &t_prev, pw)?),
                    current,
                    current_keypoint: current,
                })
            })
            .collect();
        let start = given[i - 1] * step * error;
        let pose = window
            .add(
                (&m, &MatrixK::zeros()),
                (i - 1, &given[i - 1]),
                (i, &start),
                &links,
                None,
            )
            .map_or(start, |(p, _, _)| p);
        assert!(window.len() <= keyframes.max(2));
        truth.push(t);
        given.push(pose);
    }
    (truth, given)
}

fn error_m(a: &Isometry3<f64>, b: &Isometry3<f64>) -> f64 {
    (a.translation.vector - b.translation.vector).norm()
}

#[test]
fn exact_measurements_undo_the_drift() {
    let (truth, window) = drive(3, 12);
    let (_, none) = drive(0, 12);
    let last = truth.len() - 1;
    let (e_window, e_none) = (
        error_m(&truth[last], &window[last]),
        error_m(&truth[last], &none[last]),
    );
    // Without the window the error adds up frame after frame; with it, each new frame is
    // pulled back onto the tracks seen from the window's fixed first keyframe.
    eprintln!("window {e_window} m, none {e_none} m");
    assert!(e_none > 0.1, "{e_none}");
    assert!(e_window < 1e-6, "window {e_window} m, none {e_none} m");
}

#[test]
fn a_gap_starts_the_window_again() {
    let m = model();
    let mut w = Window::new(WindowConfig {
        keyframes: 4,
        ..WindowConfig::default()
    });
    let z = StereoObservation {
        u: 600.0,
        v: 180.0,
        d: 20.0,
    };
    let link = Link {
        reference_feature: 0,
        current_feature: 0,
        reference: z,
        current: z,
        current_keypoint: z,
    };
    let id = Isometry3::identity();
    assert!(
        w.add((&m, &MatrixK::zeros()), (0, &id), (1, &id), &[link], None)
            .is_none()
    );
    assert_eq!(w.len(), 2);
    // Frame 3 measured from frame 2, which the window does not hold.
    assert!(
        w.add((&m, &MatrixK::zeros()), (2, &id), (3, &id), &[link], None)
            .is_none()
    );
    assert_eq!(w.len(), 2);
    assert_eq!(w.observations(), 2);
    w.clear();
    assert!(w.is_empty());
}

/// A camera standing still among 200 points, measured with ±0.5 px of noise and given
/// poses that drift by 1 cm and 0.05 degree a frame: no frame after the first is a
/// keyframe, so every frame is measured against the first and the drift does not add up.
#[test]
fn a_still_camera_is_measured_against_one_keyframe() {
    let m = model();
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let points = random_points_from(&mut rng, 200, 10.0, 30.0);
    let error = drift_error();
    let id = Isometry3::identity();
    let mut window = Window::new(WindowConfig::default());
    let mut given = id;
    for i in 1..30 {
        let mut noisy = |z: StereoObservation| StereoObservation {
            u: z.u + rng.random_range(-0.5..0.5),
            v: z.v + rng.random_range(-0.5..0.5),
            d: z.d + rng.random_range(-0.25..0.25),
        };
        let links: Vec<Link> = points
            .iter()
            .enumerate()
            .filter_map(|(k, pw)| {
                let z = measure(&m, &id, pw)?;
                let current = noisy(z);
                Some(Link {
                    reference_feature: k,
                    current_feature: k,
                    reference: noisy(z),
                    current,
                    current_keypoint: current,
                })
            })
            .collect();
        let start = given * error;
        let (pose, report, motion) = window
            .add(
                (&m, &MatrixK::zeros()),
                (i - 1, &given),
                (i, &start),
                &links,
                None,
            )
            .map_or((None, None, None), |(p, r, w)| (Some(p), Some(r), Some(w)));
        given = pose.unwrap_or(start);
        if i > 1 {
            let (report, motion) = (report.expect("refined"), motion.expect("refined"));
            assert!(!report.keyframe, "frame {i}");
            assert_eq!(motion.keyframe, 0, "frame {i}");
            assert_eq!(window.len(), 2, "frame {i}");
        }
    }
    let offset = given.translation.vector.norm();
    let angle = given.rotation.angle();
    eprintln!("still camera after 29 frames: {offset:.5} m, {angle:.2e} rad");
    assert!(offset < 0.005, "{offset} m");
    assert!(angle < 2e-4, "{angle} rad");
}

/// A moving camera makes every frame a keyframe; the first frame after a jump that loses
/// most tracks is one too.
#[test]
fn frames_that_move_or_lose_tracks_are_keyframes() {
    let noise = model().noise;
    let z = |u: f64| StereoObservation {
        u,
        v: 100.0,
        d: 20.0,
    };
    let frame = |obs: Vec<(u32, StereoObservation)>| Keyframe {
        index: 0,
        pose_cw: Isometry3::identity(),
        observations: obs,
        keyframe: true,
    };
    let last = frame((0..10).map(|t| (t, z(100.0 + f64::from(t)))).collect());
    let still = frame((0..10).map(|t| (t, z(100.2 + f64::from(t)))).collect());
    let moved = frame((0..10).map(|t| (t, z(105.0 + f64::from(t)))).collect());
    let new_tracks = frame((6..16).map(|t| (t, z(100.0 + f64::from(t)))).collect());
    let mut rule = KeyframeRule::default();
    assert!(!rule.is_keyframe(&last, &still, &noise));
    assert!(rule.is_keyframe(&last, &moved, &noise));
    assert!(rule.is_keyframe(&last, &new_tracks, &noise));
}
