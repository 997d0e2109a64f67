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

/// The split-feature check: with independent pixel noise of the modelled size the mean
/// normalised difference of the two halves' motions is near 6; with an error shared by
/// the features of one region (the left half's columns shifted by 0.3 px in B, the same
/// for all of them) it is far above.
#[test]
fn split_check_is_six_for_independent_noise_and_sees_a_local_bias() {
    let t = truth();
    let m = model(DisparityCorrection::default());
    let none = super::evidence::MatrixK::zeros();
    let mut honest = Vec::new();
    let mut biased = Vec::new();
    for seed in 0..40 {
        let (a, mut b) = scene(&t, &DisparityCorrection::default(), 0, 300 + seed);
        let r = refine(&m, &RefineConfig::default(), &a, &b, None, &t, 12).expect("refined");
        let check = |a: &[StereoObservation], b: &[StereoObservation], r: &Refined| {
            split::split_check(
                (&m, &none),
                &RefineConfig::default(),
                (a, b),
                &r.inliers,
                &r.motion,
                12,
            )
            .expect("both halves refined")
        };
        let c = check(&a, &b, &r);
        assert!(c.inliers.iter().all(|&n| n > 150), "{:?}", c.inliers);
        honest.push(c.nees);
        let mid = {
            let mut u: Vec<f64> = b.iter().map(|z| z.u).collect();
            u.sort_by(f64::total_cmp);
            u[u.len() / 2]
        };
        for z in b.iter_mut().filter(|z| z.u < mid) {
            z.u += 0.3;
        }
        let r = refine(&m, &RefineConfig::default(), &a, &b, None, &t, 12).expect("refined");
        biased.push(check(&a, &b, &r).nees);
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (h, b) = (mean(&honest), mean(&biased));
    eprintln!("split-feature check: mean NEES {h:.2} independent noise, {b:.1} with a local bias");
    assert!((4.5..7.5).contains(&h), "independent noise: mean NEES {h}");
    assert!(b > 12.0, "local bias: mean NEES {b}");
}

/// Bad input to the split-feature check is an error, not a panic.
#[test]
fn split_check_refuses_bad_input() {
    let t = truth();
    let (a, b) = scene(&t, &DisparityCorrection::default(), 0, 5);
    let m = model(DisparityCorrection::default());
    let none = super::evidence::MatrixK::zeros();
    let cfg = RefineConfig::default();
    let all: Vec<usize> = (0..a.len()).collect();
    let r = split::split_check((&m, &none), &cfg, (&a, &b[..10]), &all, &t, 12);
    assert!(matches!(r, Err(RefineError::LengthMismatch { .. })));
    let r = split::split_check((&m, &none), &cfg, (&a, &b), &[0, a.len()], &t, 12);
    assert!(matches!(r, Err(RefineError::LengthMismatch { .. })));
    let r = split::split_check((&m, &none), &cfg, (&a, &b), &all[..20], &t, 12);
    assert!(matches!(r, Err(RefineError::TooFewInliers { .. })));
}

/// The regions' variance factor: about 1 for independent noise of the modelled size
/// (as the residuals' `s²`); with an error shared by the features of each region (the
/// features of each cell of a 4x4 grid of B shifted together by a random 0.4 px, on top
/// of the independent 0.5 px), the covariance with the residuals' factor alone is
/// overconfident (mean NEES 70), and the regions' factor takes away about half of that
/// (34: what the motion absorbs of the regions' shifts leaves no residual to see, so a
/// residual-based factor cannot find all of it; docs/covariance.md).
#[test]
fn cluster_factor_sees_errors_shared_within_regions() {
    let t = truth();
    let m = model(DisparityCorrection::default());
    let mut independent = Vec::new();
    let (mut classic, mut regions) = (Vec::new(), Vec::new());
    let mut rng = ChaCha8Rng::seed_from_u64(77);
    let shift = Normal::new(0.0, 0.4).expect("normal");
    let nees = |r: &Refined, cov: &nalgebra::Matrix6<f64>| {
        let e = error(&r.motion, &t);
        (e.transpose() * cov.try_inverse().expect("positive definite") * e)[0]
    };
    for seed in 0..40 {
        let (a, mut b) = scene(&t, &DisparityCorrection::default(), 0, 500 + seed);
        let r = refine(&m, &RefineConfig::default(), &a, &b, None, &t, 12).expect("refined");
        independent.push(r.cluster_factor.expect("enough points"));
        let cells: Vec<(f64, f64)> = (0..16)
            .map(|_| (shift.sample(&mut rng), shift.sample(&mut rng)))
            .collect();
        for z in &mut b {
            let (i, j) = (
                ((z.u / 310.0) as usize).min(3),
                ((z.v / 92.5) as usize).min(3),
            );
            z.u += cells[4 * i + j].0;
            z.v += cells[4 * i + j].1;
        }
        let r = refine(&m, &RefineConfig::default(), &a, &b, None, &t, 12).expect("refined");
        let factor = r.cluster_factor.expect("enough points").max(r.scale2);
        regions.push(nees(&r, &r.covariance));
        classic.push(nees(&r, &(r.covariance * (r.scale2 / factor))));
    }
    let mean = |v: &[f64]| v.iter().sum::<f64>() / v.len() as f64;
    let (i, c, g) = (mean(&independent), mean(&classic), mean(&regions));
    eprintln!(
        "regions' factor {i:.2} for independent noise; shared by regions: mean NEES {c:.1} \
         with s² alone, {g:.1} with the regions' factor"
    );
    assert!((0.7..1.3).contains(&i), "independent noise: {i}");
    assert!(c > 12.0, "shared by regions, s² alone: {c}");
    assert!(
        g < 0.6 * c,
        "shared by regions, with the regions: {g} (s² alone {c})"
    );
}

/// The refinement as dispatched (compiled for the CPU's best instruction set, AVX2 where
/// there is one) gives its baseline compilation's result bit for bit (`{:?}` prints every
/// bit of a number but a NaN's sign and payload, which Rust leaves unspecified): seeded
/// scenes with wrong matches, a disparity bias, two folds, rough starts, and measurements
/// set to NaN or to zeros of both signs.
#[test]
fn the_dispatched_refinement_is_the_baseline_bit_for_bit() {
    let bias = DisparityCorrection::from_coefficients([0.7, 1.9, -0.4, 0.3, 0.8]);
    let mut rng = ChaCha8Rng::seed_from_u64(35);
    let mut refined = 0;
    for seed in 0..16 {
        let (mut a, mut b) = scene(&truth(), &bias, 40, seed);
        for _ in 0..8 {
            let i = rng.random_range(0..a.len());
            match rng.random_range(0..5) {
                0 => a[i].d = f64::NAN,
                1 => b[i].u = f64::NAN,
                2 => b[i].d = 0.0,
                3 => a[i].v = -0.0,
                _ => b[i].v = 0.0,
            }
        }
        let folds: Vec<u8> = (0..a.len()).map(|_| rng.random_range(0..2)).collect();
        let start = Isometry3::new(
            Vector3::from_fn(|_, _| rng.random_range(-0.2..0.2)) + Vector3::z() * 0.8,
            Vector3::from_fn(|_, _| rng.random_range(-0.02..0.02)),
        );
        let m = model(if seed % 2 == 0 {
            bias
        } else {
            DisparityCorrection::default()
        });
        let config = RefineConfig::default();
        let run = || refine(&m, &config, &a, &b, Some(&folds), &start, 12);
        let got = run();
        let want = swarmpose_vision::simd::baseline(run);
        assert_eq!(format!("{got:?}"), format!("{want:?}"), "seed {seed}");
        refined += usize::from(got.is_ok());
    }
    assert!(refined >= 12, "{refined} of 16 refined");
}

/// A problem over every match of a seeded scene with wrong matches and special values,
/// its points fitted to a rough start: the pose, the fits and the problem.
fn fitted_problem<'a>(
    m: &'a Prepared,
    config: &'a RefineConfig,
    (a, b): (&'a [StereoObservation], &'a [StereoObservation]),
    start: &Isometry3<f64>,
) -> (Pose, Vec<Fitted>, Problem<'a>) {
    let pose = Pose::of(&start.inverse());
    let fitted: Vec<Fitted> = a
        .iter()
        .zip(b)
        .map(|(za, zb)| fit_point(m, &pose, m.anchor(za), za, zb))
        .collect();
    let active = (0..a.len()).filter(|&i| fitted[i].is_some()).collect();
    let problem = Problem {
        model: m,
        config,
        reference: a,
        current: b,
        active,
    };
    (pose, fitted, problem)
}

/// A seeded scene with wrong matches and zeros of both signs, and a rough start.
fn rough_scene(
    seed: u64,
) -> (
    Vec<StereoObservation>,
    Vec<StereoObservation>,
    Isometry3<f64>,
) {
    let bias = DisparityCorrection::from_coefficients([0.7, 1.9, -0.4, 0.3, 0.8]);
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let (mut a, mut b) = scene(&truth(), &bias, 40, seed);
    for _ in 0..8 {
        let i = rng.random_range(0..a.len());
        match rng.random_range(0..4) {
            0 => b[i].u = -0.0,
            1 => b[i].d = 0.0,
            2 => a[i].v = -0.0,
            _ => b[i].v = -0.0,
        }
    }
    let start = Isometry3::new(
        truth().translation.vector + Vector3::from_fn(|_, _| rng.random_range(-0.1..0.1)),
        truth().rotation.scaled_axis() + Vector3::from_fn(|_, _| rng.random_range(-0.01..0.01)),
    );
    (a, b, start)
}

/// A round's first cost taken from the fits ([`Problem::gated_rounds`]) is
/// [`Problem::cost`] of the fitted points, bit for bit.
#[test]
fn the_cost_from_the_fits_is_the_cost() {
    for seed in 0..8 {
        let (a, b, start) = rough_scene(100 + seed);
        let bias = DisparityCorrection::from_coefficients([0.7, 1.9, -0.4, 0.3, 0.8]);
        let m = Prepared::new(&model(bias));
        let config = RefineConfig::default();
        let (pose, fitted, problem) = fitted_problem(&m, &config, (&a, &b), &start);
        let k = config.huber_k;
        let mut total = 0.0;
        let mut points = Vec::new();
        for &i in &problem.active {
            let (p, a2, b2) = fitted[i].expect("active");
            points.push(p);
            total += huber_cost(a2, k) + huber_cost(b2, k);
        }
        assert!(points.len() > 300, "{}", points.len());
        let want = problem.cost(&pose, &points);
        assert_eq!((0.5 * total).to_bits(), want.to_bits(), "seed {seed}");
    }
}

/// The χ² and scores taken from the linearisation of [`Problem::build`] are those of
/// [`Problem::scores`], which linearises again, bit for bit.
#[test]
fn the_scores_of_the_build_are_the_scores() {
    for seed in 0..8 {
        let (a, b, start) = rough_scene(200 + seed);
        let m = Prepared::new(&model(DisparityCorrection::from_coefficients([
            0.7, 1.9, -0.4, 0.3, 0.8,
        ])));
        let config = RefineConfig::default();
        let (pose, fitted, problem) = fitted_problem(&m, &config, (&a, &b), &start);
        let points: Vec<Vector3<f64>> = problem
            .active
            .iter()
            .filter_map(|&i| fitted[i].map(|f| f.0))
            .collect();
        let folds: Vec<u8> = (0..a.len()).map(|i| (i % 3 == 0) as u8).collect();
        let mut blocks = Vec::new();
        let mut sums = (0.0, Vec::new());
        problem
            .build(
                &pose,
                &points,
                Some(&folds),
                &mut blocks,
                Parts::All,
                Some(&mut sums),
            )
            .expect("linearised");
        let (chi2, scores) = problem.scores(&pose, &points, &blocks);
        assert_eq!(sums.0.to_bits(), chi2.to_bits(), "seed {seed}");
        assert_eq!(sums.1.len(), scores.len());
        assert!(scores.len() > 300);
        for (g, w) in sums.1.iter().zip(&scores) {
            assert_eq!(g.u.to_bits(), w.u.to_bits());
            assert_eq!(g.v.to_bits(), w.v.to_bits());
            for (x, y) in g.r.iter().zip(w.r.iter()) {
                assert_eq!(x.to_bits(), y.to_bits(), "seed {seed}");
            }
        }
    }
}

impl Problem<'_> {
    /// The Huber-weighted `χ²` of the active matches at `pose` with `points` (and their
    /// elimination `blocks`), and each match's score on the pose with its point
    /// eliminated, at its position in B ([`noise::cluster_factor`]): the refinement
    /// takes them from [`Problem::build`]'s linearisation; this computes them again,
    /// for the tests.
    fn scores(
        &self,
        pose: &Pose,
        points: &[Vector3<f64>],
        blocks: &[PoseBlocks],
    ) -> (f64, Vec<noise::Score>) {
        let k = self.config.huber_k;
        let (reference, current) = (self.reference, self.current);
        let mut chi2 = 0.0;
        let mut scores = Vec::with_capacity(self.active.len());
        for ((&i, p), b) in self.active.iter().zip(points).zip(blocks) {
            let Some((la, lb)) = linearize(
                self.model,
                pose,
                p,
                &reference[i],
                &current[i],
                Parts::PointPose,
            ) else {
                continue;
            };
            let (sa, sb) = (la.residual.norm_squared(), lb.residual.norm_squared());
            let wb = huber_weight(sb, k);
            chi2 += huber_weight(sa, k) * sa + wb * sb;
            scores.push(score(&current[i], &lb, wb, b));
        }
        (chi2, scores)
    }
}
