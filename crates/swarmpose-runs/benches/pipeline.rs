//! Throughput of the streaming engine on the 51 frames of kitti_vo_seq2 (loading, ORB
//! front end, robust PSO, reprojection refinement, online self-calibration), on one
//! thread (`track`) and on two (`run_two_threads`: loading and the front end of frame
//! k + 1 beside the back end of frame k). One iteration is the whole sequence through a
//! new engine; frames per second = 51 / time. Each with the default configuration (a
//! sliding window of 10 keyframes, [`swarmpose_odometry::window`]) and frame to frame
//! (no window). A first pass prints the per-stage split
//! and the per-frame latency (p50, p99). Needs `kitti_vo_seq2` under the data root
//! (`SWARMPOSE_DATA`); skipped with a message otherwise.
//!
//! A second group, `working_size`, runs the engine on the same frames doubled in memory
//! (bicubic, 2482x752, the calibration to match): halved back by the engine (the default
//! [`OdometryConfig::max_working_pixels`]) and at full size.
//!
//! `cargo bench -p swarmpose-runs --bench pipeline`

use std::hint::black_box;
use std::time::{Duration, Instant};

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use std::ops::ControlFlow;
use swarmpose_datasets::open;

use swarmpose_odometry::{Odometry, OdometryConfig, StageTimes, StereoInput};
use swarmpose_runs::batch::{camera_of, collect, run_sequence_two_threads};
use swarmpose_sim::stats::quantile;
use swarmpose_vision::image::{GrayImage, double};

fn bench_pipeline(c: &mut Criterion) {
    let dir = swarmpose_testdata::data_root().join("kitti_vo_seq2");
    let Ok(seq) = open(&dir) else {
        eprintln!("SKIPPED: {} not found (set SWARMPOSE_DATA)", dir.display());
        return;
    };
    let camera = camera_of(seq.as_ref());
    let config = OdometryConfig::default();
    let frames: Vec<_> = (0..seq.len()).filter_map(|i| seq.frame(i).ok()).collect();
    let variants = [
        ("", config.clone()),
        (", frame to frame", config.clone().with_window(0)),
    ];
    // Per-frame latency of the engine alone (images in memory), and the split.
    for (label, config) in &variants {
        let mut odo = Odometry::new(camera, config.clone()).expect("engine");
        let mut latency = Vec::new();
        let mut sum = StageTimes::default();
        for (i, f) in frames.iter().enumerate() {
            let t = Instant::now();
            let r = odo.track(StereoInput {
                left: f.left.view(),
                right: f.right.view(),
                timestamp_s: i as f64 * 0.1,
            });
            latency.push(t.elapsed().as_secs_f64() * 1e3);
            if let Ok(r) = r {
                sum += &r.times;
            }
        }
        let n = latency.len() as f64;
        latency.sort_by(f64::total_cmp);
        eprintln!(
            "kitti_vo_seq2, orb + pso{label}, engine per frame (images in memory): p50 {:.1} ms, \
             p99 {:.1} ms; mean features {:.2}, stereo {:.2}, match {:.2}, estimate {:.2}, \
             refine {:.2}, calibrate {:.2}, window {:.2} ms",
            quantile(&latency, 0.5),
            quantile(&latency, 0.99),
            sum.features_ms / n,
            sum.stereo_ms / n,
            sum.match_ms / n,
            sum.estimate_ms / n,
            sum.refine_ms / n,
            sum.calibrate_ms / n,
            sum.window_ms / n,
        );
    }
    let mut g = c.benchmark_group("odometry");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(20));
    g.throughput(Throughput::Elements(seq.len() as u64));
    for (label, config) in &variants {
        g.bench_function(format!("kitti_vo_seq2/load+engine{label}"), |b| {
            b.iter(|| {
                let mut odo = Odometry::new(camera, config.clone()).expect("engine");
                black_box(collect(seq.as_ref(), &mut odo, 0.1))
            });
        });
        g.bench_function(
            format!("kitti_vo_seq2/load+engine{label}, two threads"),
            |b| {
                b.iter(|| {
                    let mut odo = Odometry::new(camera, config.clone()).expect("engine");
                    let mut n = 0;
                    run_sequence_two_threads(seq.as_ref(), &mut odo, 0.1, &mut |r| {
                        n += black_box(r.index);
                        ControlFlow::Continue(())
                    })
                    .expect("run");
                    n
                });
            },
        );
    }
    g.bench_function("kitti_vo_seq2/engine", |b| {
        b.iter(|| {
            let mut odo = Odometry::new(camera, config.clone()).expect("engine");
            for (i, f) in frames.iter().enumerate() {
                let _ = black_box(odo.track(StereoInput {
                    left: f.left.view(),
                    right: f.right.view(),
                    timestamp_s: i as f64 * 0.1,
                }));
            }
        });
    });
    g.finish();
}

/// The engine (images in memory) on kitti_vo_seq2 doubled: halved back by the engine
/// (default) and at full size (`max_working_pixels = usize::MAX`).
fn bench_working_size(c: &mut Criterion) {
    let dir = swarmpose_testdata::data_root().join("kitti_vo_seq2");
    let Ok(seq) = open(&dir) else {
        eprintln!("SKIPPED: {} not found (set SWARMPOSE_DATA)", dir.display());
        return;
    };
    let camera = camera_of(seq.as_ref()).doubled();
    let (mut tmp, mut out) = (Vec::new(), Vec::new());
    let mut doubled = |img: &GrayImage| {
        let (w, h) = double(img.view(), &mut tmp, &mut out);
        GrayImage::from_raw(w, h, out.clone()).expect("size")
    };
    let frames: Vec<(GrayImage, GrayImage)> = (0..seq.len())
        .filter_map(|i| seq.frame(i).ok())
        .map(|f| (doubled(&f.left), doubled(&f.right)))
        .collect();
    let mut g = c.benchmark_group("working_size");
    g.sample_size(10);
    g.measurement_time(Duration::from_secs(30));
    g.throughput(Throughput::Elements(frames.len() as u64));
    let variants = [
        ("halved by the engine (default)", OdometryConfig::default()),
        (
            "full size",
            OdometryConfig {
                max_working_pixels: usize::MAX,
                ..OdometryConfig::default()
            },
        ),
    ];
    for (label, config) in &variants {
        g.bench_function(format!("kitti_vo_seq2 2482x752/engine, {label}"), |b| {
            b.iter(|| {
                let mut odo = Odometry::new(camera, config.clone()).expect("engine");
                for (i, (l, r)) in frames.iter().enumerate() {
                    let _ = black_box(odo.track(StereoInput {
                        left: l.view(),
                        right: r.view(),
                        timestamp_s: i as f64 * 0.1,
                    }));
                }
            });
        });
    }
    g.finish();
}

criterion_group!(benches, bench_pipeline, bench_working_size);
criterion_main!(benches);
