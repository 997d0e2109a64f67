use nalgebra::{Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use swarmpose_vision::frontend::DisparityCorrection;
use swarmpose_vision::stereo::RectifiedStereo;

use super::model::{PixelNoise, StereoModel, StereoObservation};
use super::*;

const RIG: RectifiedStereo = RectifiedStereo {
    fx: 700.0,
    fy: 700.0,
    cx: 620.0,
    cy: 185.0,
    baseline_m: 0.54,
};
const NOISE: PixelNoise = PixelNoise {
    position_px: 0.5,
    disparity_px: 0.25,
};

/// Measures `p` (left camera frame) with noise, the true disparity short by `bias`.
fn measure(
    p: &Point3<f64>,
    bias: &DisparityCorrection,
    rng: &mut ChaCha8Rng,
    noise: &PixelNoise,
) -> Option<StereoObservation> {
    if p.z < 1.0 {
        return None;
    }
    let (u, v) = RIG.project_left(p);
    if !(0.0..1240.0).contains(&u) || !(0.0..370.0).contains(&v) {
        return None;
    }
    let d = RIG.fx * RIG.baseline_m / p.z - bias.at(p, RIG.baseline_m);
    let np = Normal::new(0.0, noise.position_px).ok()?;
    let nd = Normal::new(0.0, noise.disparity_px).ok()?;
    let d = d + nd.sample(rng);
    (d > 0.5).then(|| StereoObservation {
        u: u + np.sample(rng),
        v: v + np.sample(rng),
        d,
    })
}

/// Matches of a street-like scene seen from A and from B (`motion` = pose of B in A),
/// with `outliers` wrong matches.
fn scene(
    motion: &Isometry3<f64>,
    bias: &DisparityCorrection,
    outliers: usize,
    seed: u64,
) -> (Vec<StereoObservation>, Vec<StereoObservation>) {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut a, mut b) = (Vec::new(), Vec::new());
    let inv = motion.inverse();
    while a.len() < 400 {
        let p = Point3::new(
            rng.random_range(-15.0..15.0),
            rng.random_range(-3.0..1.7),
            rng.random_range(4.0..60.0),
        );
        let (Some(za), Some(zb)) = (
            measure(&p, bias, &mut rng, &NOISE),
            measure(&(inv * p), bias, &mut rng, &NOISE),
        ) else {
            continue;
        };
        a.push(za);
        b.push(zb);
    }
    for k in 0..outliers {
        let j = (k * 7919 + 13) % a.len();
        b[j].u = rng.random_range(0.0..1240.0);
        b[j].v = rng.random_range(0.0..370.0);
    }
    (a, b)
}

fn model(correction: DisparityCorrection) -> StereoModel {
    StereoModel {
        rig: RIG,
        noise: NOISE,
        correction,
    }
}

fn truth() -> Isometry3<f64> {
    Isometry3::new(
        Vector3::new(0.05, -0.02, 0.9),
        Vector3::new(0.003, 0.02, -0.002),
    )
}

/// The error `ξ` with `T_true = T_est ∘ E(ξ)`.
fn error(est: &Isometry3<f64>, truth: &Isometry3<f64>) -> Vector6<f64> {
    let r = est.rotation.inverse() * truth.rotation;
    let nu = est.rotation.inverse() * (truth.translation.vector - est.translation.vector);
    let w = r.scaled_axis();
    Vector6::new(nu.x, nu.y, nu.z, w.x, w.y, w.z)
}

#[test]
fn recovers_the_motion_from_a_rough_start_and_rejects_wrong_matches() {
    let t = truth();
    let (a, b) = scene(&t, &DisparityCorrection::default(), 80, 1);
    let start = Isometry3::new(Vector3::new(0.1, 0.05, 0.8), Vector3::new(0.0, 0.01, 0.0));
    let m = model(DisparityCorrection::default());
    let r = refine(&m, &RefineConfig::default(), &a, &b, None, &start, 12).expect("refined");
    let e = error(&r.motion, &t);
    assert!(e.fixed_rows::<3>(0).norm() < 0.02, "translation error {e}");
    assert!(e.fixed_rows::<3>(3).norm() < 1e-3, "rotation error {e}");
    // The wrong matches are gone, nearly every right one kept.
    let wrong: Vec<usize> = (0..80).map(|k| (k * 7919 + 13) % a.len()).collect();
    let kept_wrong = r.inliers.iter().filter(|i| wrong.contains(i)).count();
    assert!(kept_wrong <= 2, "{kept_wrong} wrong matches kept");
    assert!(r.inliers.len() >= 300, "{} inliers", r.inliers.len());
    assert!(
        (0.7..1.3).contains(&r.scale2),
        "variance factor {}",
        r.scale2
    );
}

/// The covariance is honest: the mean normalised estimation error squared over many
/// scenes is close to 6, its number of degrees of freedom.
#[test]
fn covariance_is_consistent() {
    let t = truth();
    let m = model(DisparityCorrection::default());
    let runs = 60;
    let mut nees = 0.0;
    for seed in 0..runs {
        let (a, b) = scene(&t, &DisparityCorrection::default(), 20, 100 + seed);
        let r = refine(&m, &RefineConfig::default(), &a, &b, None, &t, 12).expect("refined");
        let e = error(&r.motion, &t);
        let w = r.covariance.try_inverse().expect("positive definite");
        nees += (e.transpose() * w * e)[0];
    }
    let mean = nees / runs as f64;
    assert!((4.5..7.5).contains(&mean), "mean NEES {mean}");
}

/// A disparity bias the model does not know: the profile cost's gradient points
/// towards it, and the quadratic model's minimiser finds it.
#[test]
fn reduced_equations_locate_a_disparity_offset() {
    let t = truth();
    let bias = DisparityCorrection::constant(1.0);
    let (a, b) = scene(&t, &bias, 0, 7);
    let m = model(DisparityCorrection::default());
    let r = refine(&m, &RefineConfig::default(), &a, &b, None, &t, 12).expect("refined");
    let (info, grad) = r.reduced[0].profile().expect("regular");
    // Constant model: a = -γ_a / I_aa from c = 0.
    let a_hat = -grad[0] / info[(0, 0)];
    assert!((a_hat - 1.0).abs() < 0.15, "offset {a_hat}");
    // Knowing the offset, the motion is recovered.
    let m1 = model(bias);
    let r1 = refine(&m1, &RefineConfig::default(), &a, &b, None, &t, 12).expect("refined");
    let e = error(&r1.motion, &t);
    assert!(e.fixed_rows::<3>(0).norm() < 0.01, "{e}");
}

#[test]
fn too_few_points_is_an_error_not_a_pose() {
    let t = truth();
    let (a, b) = scene(&t, &DisparityCorrection::default(), 0, 3);
    let m = model(DisparityCorrection::default());
    let r = refine(&m, &RefineConfig::default(), &a[..5], &b[..5], None, &t, 12);
    assert!(matches!(
        r,
        Err(RefineError::TooFewInliers { got: 5, needed: 12 })
    ));
    let r = refine(&m, &RefineConfig::default(), &a[..5], &b[..4], None, &t, 12);
    assert!(matches!(r, Err(RefineError::LengthMismatch { .. })));
}
