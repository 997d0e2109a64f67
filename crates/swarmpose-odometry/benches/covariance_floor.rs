//! The cost of the systematic floor of the covariance ([`swarmpose_odometry::refine::floor`]):
//! the split-feature check it runs on every refined pair (each half of the inliers refined
//! again from the pair's motion) beside the pair's own refinement, and the floor's update,
//! on a street-like pair of 400 matches (0.5 px noise, KITTI's rig, 0.9 m forward).
//!
//! `cargo bench -p swarmpose-odometry --bench covariance_floor`

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{Isometry3, Point3, Vector3};
use rand::{RngExt, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use swarmpose_odometry::refine::evidence::MatrixK;
use swarmpose_odometry::refine::floor::{FloorConfig, SystematicFloor};
use swarmpose_odometry::refine::model::{PixelNoise, StereoModel, StereoObservation};
use swarmpose_odometry::refine::split::split_check;
use swarmpose_odometry::refine::{RefineConfig, refine};
use swarmpose_vision::frontend::DisparityCorrection;
use swarmpose_vision::stereo::RectifiedStereo;

const RIG: RectifiedStereo = RectifiedStereo {
    fx: 718.856,
    fy: 718.856,
    cx: 607.19,
    cy: 185.22,
    baseline_m: 0.537,
};
const NOISE: PixelNoise = PixelNoise {
    position_px: 0.5,
    disparity_px: 0.25,
};

/// A measurement of `p` (left camera frame, metres) with noise, or `None` outside the
/// image or too far.
fn measure(p: &Point3<f64>, rng: &mut ChaCha8Rng, n: &Normal<f64>) -> Option<StereoObservation> {
    let (u, v) = RIG.project_left(p);
    let d = RIG.fx * RIG.baseline_m / p.z;
    ((0.0..1241.0).contains(&u) && (0.0..376.0).contains(&v) && d > 1.0).then(|| {
        StereoObservation {
            u: u + n.sample(rng),
            v: v + n.sample(rng),
            d: d + 0.5 * n.sample(rng),
        }
    })
}

/// 400 matches of a street seen from A and from B (`motion`: pose of B in A).
fn pair(motion: &Isometry3<f64>) -> (Vec<StereoObservation>, Vec<StereoObservation>) {
    let mut rng = ChaCha8Rng::seed_from_u64(35);
    let n = Normal::new(0.0, NOISE.position_px).expect("normal");
    let inv = motion.inverse();
    let (mut a, mut b) = (Vec::new(), Vec::new());
    while a.len() < 400 {
        let p = Point3::new(
            rng.random_range(-15.0..15.0),
            rng.random_range(-3.0..1.7),
            rng.random_range(4.0..60.0),
        );
        if let (Some(za), Some(zb)) = (measure(&p, &mut rng, &n), measure(&(inv * p), &mut rng, &n))
        {
            a.push(za);
            b.push(zb);
        }
    }
    (a, b)
}

fn bench_floor(c: &mut Criterion) {
    let truth = Isometry3::new(
        Vector3::new(0.05, -0.02, 0.9),
        Vector3::new(0.003, 0.02, -0.002),
    );
    let (a, b) = pair(&truth);
    let model = StereoModel {
        rig: RIG,
        noise: NOISE,
        correction: DisparityCorrection::default(),
    };
    let config = RefineConfig::default();
    let calibration = MatrixK::zeros();
    let refined = refine(&model, &config, &a, &b, None, &truth, 12).expect("refined");
    let check = || {
        split_check(
            (&model, &calibration),
            &config,
            (&a, &b),
            &refined.inliers,
            &refined.motion,
            12,
        )
        .expect("both halves refined")
    };
    let raw = check();
    let mut g = c.benchmark_group("covariance_floor");
    g.sample_size(20);
    g.measurement_time(Duration::from_secs(5));
    g.bench_function("pair refinement (400 matches)", |bench| {
        bench.iter(|| black_box(refine(&model, &config, &a, &b, None, &truth, 12)));
    });
    g.bench_function("split check (two half refinements)", |bench| {
        bench.iter(|| black_box(check()));
    });
    g.bench_function("floor judge + learn", |bench| {
        let mut floor = SystematicFloor::new(FloorConfig::default());
        bench.iter(|| {
            let judged = floor.judge(black_box(&raw));
            floor.learn(&raw);
            black_box(judged)
        });
    });
    g.finish();
}

criterion_group!(benches, bench_floor);
criterion_main!(benches);
