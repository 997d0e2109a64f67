//! Criterion benchmarks of the default `pso` on stereo-noise scenes (`StereoSpec::street`):
//! 600 correspondences at 90 % and 97 % outliers and 20 000 at 90 %, each with the
//! covariances, as plain coordinates, and as plain coordinates with the range noise model
//! turned off (`plain_isotropic`: what the model costs), one thread.
//!
//! `cargo bench -p swarmpose-sim --bench stereo`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use swarmpose_core::{Estimator, PsoEstimator, PsoEstimatorConfig};
use swarmpose_sim::StereoSpec;

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("pso_stereo");
    group.sample_size(20);
    for (n, outliers) in [(600usize, 0.9), (600, 0.97), (20_000, 0.9)] {
        let s = StereoSpec::street()
            .with_n(n)
            .with_outliers(outliers)
            .scenario(42)
            .expect("valid spec");
        let plain = s.plain().expect("valid points");
        let pso = PsoEstimator::default();
        let id = format!("n{n}_outliers{:.0}", outliers * 100.0);
        group.bench_with_input(BenchmarkId::new("covariances", &id), &s.data, |b, d| {
            b.iter(|| std::hint::black_box(pso.estimate_seeded(d, 7)));
        });
        group.bench_with_input(BenchmarkId::new("plain", &id), &plain, |b, d| {
            b.iter(|| std::hint::black_box(pso.estimate_seeded(d, 7)));
        });
        let isotropic = PsoEstimator::new(PsoEstimatorConfig::default().with_range_noise(false));
        group.bench_with_input(BenchmarkId::new("plain_isotropic", &id), &plain, |b, d| {
            b.iter(|| std::hint::black_box(isotropic.estimate_seeded(d, 7)));
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
