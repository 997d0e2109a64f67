//! Success rate, accuracy and time of every estimator against the outlier fraction on
//! synthetic data: `cargo run --release -p swarmpose-core --example sweep [noise_m] [runs]`.

use std::time::Instant;

use swarmpose_core::geometry::rotation_angle_between;
use swarmpose_core::synthetic::SyntheticSpec;
use swarmpose_core::{Estimator, MsacEstimator, PsoEstimator, PsoPaperEstimator, SvdEstimator};

fn median(v: &mut [f64]) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
    let noise: f64 = args.get(1).and_then(|a| a.parse().ok()).unwrap_or(0.02);
    let runs: u64 = args.get(2).and_then(|a| a.parse().ok()).unwrap_or(50);
    let threshold = (3.368 * noise).max(0.01);
    let estimators: Vec<Box<dyn Estimator>> = vec![
        Box::new(PsoEstimator::new(
            swarmpose_core::PsoEstimatorConfig::default().with_threshold(threshold),
        )),
        Box::new(PsoPaperEstimator::new(
            swarmpose_core::PsoPaperConfig::default().with_threshold(threshold),
        )),
        Box::new(SvdEstimator),
        Box::new(MsacEstimator::new(
            swarmpose_core::MsacConfig::default().with_threshold(threshold),
        )),
    ];
    println!("noise {noise} m, threshold {threshold:.3} m, {runs} runs, 200 correspondences");
    println!("| method | outliers | success % | median rot deg | median trans m | median ms |");
    println!("|---|---|---|---|---|---|");
    for e in &estimators {
        for frac in [0.0, 0.1, 0.3, 0.5, 0.7, 0.8, 0.9, 0.95] {
            let spec = SyntheticSpec {
                noise_sigma_m: noise,
                outlier_fraction: frac,
                ..Default::default()
            };
            let (mut rot, mut trans, mut ms) = (vec![], vec![], vec![]);
            let mut ok = 0;
            for run in 0..runs {
                let s = spec.generate(1000 + run).expect("valid");
                let t0 = Instant::now();
                let out = e.estimate_seeded(&s.data, run);
                ms.push(t0.elapsed().as_secs_f64() * 1e3);
                if let Ok(out) = out {
                    let r = rotation_angle_between(&out.transform.rotation, &s.truth.rotation)
                        .to_degrees();
                    let t = (out.transform.translation.vector - s.truth.translation.vector).norm();
                    rot.push(r);
                    trans.push(t);
                    if r < 2.0 && t < 0.2 {
                        ok += 1;
                    }
                }
            }
            println!(
                "| {} | {frac} | {:.0} | {:.3} | {:.3} | {:.3} |",
                e.name(),
                100.0 * ok as f64 / runs as f64,
                median(&mut rot),
                median(&mut trans),
                median(&mut ms)
            );
        }
    }
}
