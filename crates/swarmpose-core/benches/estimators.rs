//! Criterion benchmarks of the estimators on synthetic data (noise 0.02 m, threshold
//! 0.07 m): 200 and 2000 correspondences at 0 % and 50 % random outliers, one thread; and
//! `pso` at 90 / 95 % outliers (200 correspondences) and 90 % (5000).
//!
//! `cargo bench -p swarmpose-core --bench estimators`

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use swarmpose_core::synthetic::SyntheticSpec;
use swarmpose_core::{
    Estimator, MsacConfig, MsacEstimator, PsoEstimator, PsoEstimatorConfig, PsoPaperConfig,
    PsoPaperEstimator, SvdEstimator,
};

fn estimators(threshold_m: f64) -> Vec<Box<dyn Estimator>> {
    vec![
        Box::new(PsoEstimator::new(
            PsoEstimatorConfig::default().with_threshold(threshold_m),
        )),
        Box::new(PsoPaperEstimator::new(
            PsoPaperConfig::default().with_threshold(threshold_m),
        )),
        Box::new(SvdEstimator),
        Box::new(MsacEstimator::new(
            MsacConfig::default().with_threshold(threshold_m),
        )),
    ]
}

fn bench(c: &mut Criterion) {
    for n in [200usize, 2000] {
        for outliers in [0.0, 0.5] {
            let spec = SyntheticSpec {
                n,
                outlier_fraction: outliers,
                ..Default::default()
            };
            let scenario = spec.generate(42).expect("valid spec");
            let mut group = c.benchmark_group(format!("n{n}_outliers{:.0}", outliers * 100.0));
            group.sample_size(30);
            for e in estimators(0.07) {
                group.bench_with_input(
                    BenchmarkId::from_parameter(e.name()),
                    &scenario.data,
                    |b, data| {
                        // pso-paper may fail at 50 % outliers (see its docs); its time counts all the same.
                        b.iter(|| std::hint::black_box(e.estimate_seeded(data, 7)));
                    },
                );
            }
            group.finish();
        }
    }
}

/// The robust estimator where the peers are slow: 200 correspondences at 90 and 95 %
/// outliers, and 5000 at 90 %.
fn bench_high_outliers(c: &mut Criterion) {
    let mut group = c.benchmark_group("pso_high_outliers");
    group.sample_size(30);
    for (n, outliers) in [(200usize, 0.9), (200, 0.95), (5000, 0.9)] {
        let spec = SyntheticSpec {
            n,
            outlier_fraction: outliers,
            ..Default::default()
        };
        let data = spec.generate(42).expect("valid spec").data;
        let pso = PsoEstimator::new(PsoEstimatorConfig::default().with_threshold(0.07));
        let auto = PsoEstimator::default();
        let id = format!("n{n}_outliers{:.0}", outliers * 100.0);
        group.bench_with_input(BenchmarkId::new("pso", &id), &data, |b, d| {
            b.iter(|| std::hint::black_box(pso.estimate_seeded(d, 7)));
        });
        group.bench_with_input(
            BenchmarkId::new("pso_auto_threshold", &id),
            &data,
            |b, d| {
                b.iter(|| std::hint::black_box(auto.estimate_seeded(d, 7)));
            },
        );
    }
    group.finish();
}

criterion_group!(benches, bench, bench_high_outliers);
criterion_main!(benches);
