//! Throughput of the whole odometry pipeline (load, ORB front end, robust PSO with
//! stereo noise, offset self-calibration, refinement, chaining) on the 51 frames of
//! kitti_vo_seq2, one thread (nothing in the pipeline spawns threads). One iteration is
//! the whole sequence; frames per second = 51 / time. The per-stage split is printed
//! once. Needs `kitti_vo_seq2` under the data root (`SWARMPOSE_DATA`); skipped with a
//! message otherwise.
//!
//! `cargo bench -p swarmpose-odometry --bench pipeline`

use std::hint::black_box;
use std::time::Duration;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use swarmpose_core::{PsoEstimator, PsoEstimatorConfig};
use swarmpose_datasets::open;
use swarmpose_odometry::{OdometryConfig, run};
use swarmpose_vision::frontend::Frontend;

fn bench_pipeline(c: &mut Criterion) {
    let dir = swarmpose_datasets::data_root().join("kitti_vo_seq2");
    let Ok(seq) = open(&dir) else {
        eprintln!("SKIPPED: {} not found (set SWARMPOSE_DATA)", dir.display());
        return;
    };
    let frontend = Frontend::orb(seq.calibration());
    let estimator = PsoEstimator::new(PsoEstimatorConfig::default());
    let config = OdometryConfig::default();
    let once = run(seq.as_ref(), &frontend, &estimator, &config, &mut |_, _| {});
    if let Ok(r) = &once {
        let n = r.frames.len() as f64;
        let mean = |f: &dyn Fn(&swarmpose_odometry::StageTimes) -> f64| {
            r.frames.iter().map(|x| f(&x.times)).sum::<f64>() / n
        };
        let total = mean(&|t| t.total_ms());
        eprintln!(
            "kitti_vo_seq2, orb + pso, per frame: total {total:.2} ms ({:.1} frames/s); load {:.2}, \
             features {:.2}, stereo {:.2}, match {:.2}, estimate {:.2}, refine {:.2} ms",
            1000.0 / total,
            mean(&|t| t.load_ms),
            mean(&|t| t.features_ms),
            mean(&|t| t.stereo_ms),
            mean(&|t| t.match_ms),
            mean(&|t| t.estimate_ms),
            mean(&|t| t.refine_ms),
        );
    }
    let mut g = c.benchmark_group("odometry");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    g.throughput(Throughput::Elements(seq.len() as u64));
    g.bench_function("kitti_vo_seq2/orb+pso", |b| {
        b.iter(|| {
            black_box(run(
                seq.as_ref(),
                &frontend,
                &estimator,
                &config,
                &mut |_, _| {},
            ))
        });
    });
    g.finish();
}

criterion_group!(benches, bench_pipeline);
criterion_main!(benches);
