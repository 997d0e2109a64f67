//! SURF timings on the first left KITTI frame (1241 × 376):
//! `cargo bench -p swarmpose-vision --bench surf`.
//!
//! A plain timing loop (no benchmark framework): each stage runs `ROUNDS` times and the
//! median and minimum wall-clock times are printed. The image is
//! `$SWARMPOSE_DATA/kitti_vo_seq2/image_0/000000.png` (default data root
//! `../../../shared/data` from this crate); without it the bench prints why and exits.
//!
//! The "paper" configuration turns off the smoothed octaves and the finest-layer maxima
//! (with the threshold of the former default, 0.0004), to show what they cost.

use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::time::Instant;

use swarmpose_vision::features::{FeatureExtractor, GrayView};
use swarmpose_vision::surf::integral::IntegralImage;
use swarmpose_vision::surf::{Surf, SurfConfig};

const ROUNDS: usize = 15;

/// Median and minimum of `ROUNDS` runs of `f`, milliseconds.
fn time<T>(mut f: impl FnMut() -> T) -> (f64, f64) {
    black_box(f());
    let mut ms: Vec<f64> = (0..ROUNDS)
        .map(|_| {
            let start = Instant::now();
            black_box(f());
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    ms.sort_by(f64::total_cmp);
    (ms[ROUNDS / 2], ms[0])
}

fn main() {
    let root = std::env::var_os("SWARMPOSE_DATA").map_or_else(
        || Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data"),
        PathBuf::from,
    );
    let path = root.join("kitti_vo_seq2/image_0/000000.png");
    let img = match image::open(&path) {
        Ok(img) => img.to_luma8(),
        Err(e) => {
            println!("surf bench skipped: cannot read {}: {e}", path.display());
            return;
        }
    };
    let (w, h) = (img.width() as usize, img.height() as usize);
    let data = img.into_raw();
    let view = GrayView {
        width: w,
        height: h,
        data: &data,
    };
    println!("SURF on {} ({w}x{h}), {ROUNDS} rounds", path.display());
    let report = |name: &str, (median, min): (f64, f64), count: usize| {
        println!("{name:<36} median {median:7.2} ms   min {min:7.2} ms   ({count} features)");
    };
    report("integral image", time(|| IntegralImage::new(view)), 0);
    for (name, config) in [
        ("surf (default)", SurfConfig::default()),
        ("upright-surf", SurfConfig::upright()),
        (
            "upright-surf, paper",
            SurfConfig {
                smoothing: 0.0,
                finest_layer_maxima: false,
                hessian_threshold: 0.0004,
                ..SurfConfig::upright()
            },
        ),
        (
            "surf, initial step 2",
            SurfConfig {
                initial_step: 2,
                ..SurfConfig::default()
            },
        ),
        (
            "surf, best 500",
            SurfConfig {
                max_features: Some(500),
                ..SurfConfig::default()
            },
        ),
    ] {
        let surf = Surf::new(config);
        let count = surf.extract(view).len();
        report(
            &format!("{name}: detect"),
            time(|| surf.detect(view)),
            count,
        );
        report(
            &format!("{name}: extract"),
            time(|| surf.extract(view)),
            count,
        );
    }
}
