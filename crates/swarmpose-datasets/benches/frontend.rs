//! The stereo front end per KITTI stereo pair (1241 x 376), stage by stage, for both
//! detectors: load (two PNGs), detect (left + right), describe (left + right), stereo
//! match (with sub-pixel refinement and triangulation), temporal match (against the
//! previous frame). One thread. Needs `kitti_vo_seq2` under the data root
//! (`SWARMPOSE_DATA`); skipped with a message otherwise.
//!
//! `cargo bench -p swarmpose-datasets --bench frontend`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use swarmpose_datasets::open;
use swarmpose_vision::features::{FeatureExtractor, Features};
use swarmpose_vision::frontend::Frontend;

fn bench_frontend(c: &mut Criterion) {
    let dir = swarmpose_testdata::data_root().join("kitti_vo_seq2");
    let Ok(seq) = open(&dir) else {
        eprintln!("SKIPPED: {} not found (set SWARMPOSE_DATA)", dir.display());
        return;
    };
    let (a, b) = match (seq.frame(10), seq.frame(11)) {
        (Ok(a), Ok(b)) => (a, b),
        _ => {
            eprintln!("SKIPPED: frames of {} unreadable", dir.display());
            return;
        }
    };
    let rig = seq.calibration();
    let mut g = c.benchmark_group("frontend");
    g.sample_size(20);

    g.bench_function("load", |bench| {
        bench.iter(|| black_box(seq.frame(black_box(11))))
    });

    // ORB: detect and describe separately.
    let orb = Frontend::orb(rig);
    let right_orb = orb
        .right_extractor
        .clone()
        .unwrap_or_else(|| orb.extractor.clone());
    g.bench_function("orb/detect", |bench| {
        bench.iter(|| {
            (
                orb.extractor.detect(b.left.view()),
                right_orb.detect(b.right.view()),
            )
        })
    });
    let (kl, kr) = (
        orb.extractor.detect(b.left.view()),
        right_orb.detect(b.right.view()),
    );
    g.bench_function("orb/describe", |bench| {
        bench.iter(|| {
            (
                orb.extractor.describe(b.left.view(), &kl),
                right_orb.describe(b.right.view(), &kr),
            )
        })
    });
    let (lf, rf) = (
        orb.extract(b.left.view()),
        orb.extract_right(b.right.view()),
    );
    g.bench_function("orb/stereo_match", |bench| {
        bench.iter(|| orb.stereo_from_features(&lf, &rf, b.left.view(), b.right.view()))
    });
    let fa = orb.stereo_frame(a.left.view(), a.right.view());
    let fb = orb.stereo_from_features(&lf, &rf, b.left.view(), b.right.view());
    g.bench_function("orb/temporal_match", |bench| {
        bench.iter(|| orb.match_frames(&fa, &fb))
    });
    g.bench_function("orb/pair_total", |bench| {
        bench.iter(|| {
            let f = orb.stereo_frame(b.left.view(), b.right.view());
            orb.match_frames(&fa, &f)
        })
    });

    // SURF (upright, the odometry configuration of `Frontend::surf`): detection alone,
    // and detection + description.
    let surf = Frontend::surf(rig);
    g.bench_function("surf/detect", |bench| {
        bench.iter(|| {
            (
                surf.extractor.detect(b.left.view()),
                surf.extractor.detect(b.right.view()),
            )
        })
    });
    g.bench_function("surf/detect_and_describe", |bench| {
        bench.iter(|| {
            (
                surf.extractor.extract(b.left.view()),
                surf.extractor.extract(b.right.view()),
            )
        })
    });
    let (sl, sr): (Features<_>, Features<_>) = (
        surf.extract(b.left.view()),
        surf.extract_right(b.right.view()),
    );
    g.bench_function("surf/stereo_match", |bench| {
        bench.iter(|| surf.stereo_from_features(&sl, &sr, b.left.view(), b.right.view()))
    });
    let sa = surf.stereo_frame(a.left.view(), a.right.view());
    let sb = surf.stereo_from_features(&sl, &sr, b.left.view(), b.right.view());
    g.bench_function("surf/temporal_match", |bench| {
        bench.iter(|| surf.match_frames(&sa, &sb))
    });
    g.finish();
    eprintln!(
        "features per pair: orb left {} right {} stereo {}; surf left {} right {} stereo {}",
        lf.len(),
        rf.len(),
        fb.len(),
        sl.len(),
        sr.len(),
        sb.len()
    );
}

criterion_group!(benches, bench_frontend);
criterion_main!(benches);
