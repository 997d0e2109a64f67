//! `pso` on the stereo-noise generator: measurement scripts that print success tables
//! (they assert nothing, so they are an example rather than tests). Run one with
//! `cargo run --release -p swarmpose-sim --example stereo_sweep -- NAME`, NAME one of
//! `sweep` (`RUNS` seeds per cell, default 20), `debug` (per-seed diagnostics at the
//! outlier fraction `FRAC`, default 0.95), `large` (20 000 rows), `noisy` (isotropic
//! noise of 0.3 and 1 m) or `timing-inputs` (writes the timing inputs to `$STEREO_OUT`).
#![allow(clippy::unwrap_used)]

use swarmpose_core::{Estimator, PsoEstimator, WlsEstimator};
use swarmpose_sim::StereoSpec;

/// (right, wrong plain successes, errors) over `runs` seeds.
fn count(spec: &StereoSpec, runs: u64, covariances: bool) -> (usize, usize, usize, usize) {
    let (mut ok, mut wrong, mut err, mut oracle) = (0, 0, 0, 0);
    for seed in 0..runs {
        let s = spec.scenario(1000 + seed).unwrap();
        let data = if covariances {
            s.data.clone()
        } else {
            s.plain().unwrap()
        };
        match PsoEstimator::default().estimate_seeded(&data, seed) {
            Ok(e) if s.is_success(&e.transform) => ok += 1,
            Ok(_) => wrong += 1,
            Err(_) => err += 1,
        }
        let sel = s.data.select(&s.inlier_indices());
        oracle += usize::from(
            WlsEstimator
                .estimate_seeded(&sel, 0)
                .is_ok_and(|e| s.is_success(&e.transform)),
        );
    }
    (ok, wrong, err, oracle)
}

fn stereo_sweep() {
    let runs: u64 = std::env::var("RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    for (name, spec) in [
        ("street", StereoSpec::street()),
        ("room", StereoSpec::room()),
        ("tabletop", StereoSpec::tabletop()),
        ("street mm", StereoSpec::street().with_unit(1000.0)),
    ] {
        for f in [0.9, 0.95, 0.97] {
            let spec = spec.clone().with_outliers(f);
            let (a, aw, ae, o) = count(&spec, runs, false);
            let (b, bw, be, _) = count(&spec, runs, true);
            println!(
                "{name:10} {f:.2}: plain {a}/{runs} (wrong {aw}, err {ae}) | cov {b}/{runs} (wrong {bw}, err {be}) | oracle-weighted {o}/{runs}"
            );
        }
    }
}

fn stereo_debug() {
    let f: f64 = std::env::var("FRAC")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.95);
    let spec = StereoSpec::street().with_outliers(f);
    let runs: u64 = std::env::var("RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(8);
    for seed in 0..runs {
        let s = spec.scenario(1000 + seed).unwrap();
        let ninl = s.inlier.iter().filter(|&&b| b).count();
        eprintln!(
            "seed {seed}: truth {:?} {:?} true inliers {ninl}",
            s.truth.rotation.scaled_axis(),
            s.truth.translation.vector
        );
        let n: usize = std::env::var("N")
            .ok()
            .and_then(|v| v.parse().ok())
            .unwrap_or(600);
        let s = if n == 600 {
            s
        } else {
            spec.clone().with_n(n).scenario(3000 + seed).unwrap()
        };
        let data = if std::env::var("COV").is_ok() {
            s.data.clone()
        } else {
            s.plain().unwrap()
        };
        let r = PsoEstimator::default().estimate_seeded(&data, seed);
        match r {
            Ok(e) => {
                let good = e.inliers.iter().filter(|&&i| s.inlier[i]).count();
                eprintln!(
                    "  ok={} inliers {} (true {good}) rot {:.2} tr {:.3} thr {:?}",
                    s.is_success(&e.transform),
                    e.inliers.len(),
                    swarmpose_core::geometry::rotation_angle_between(
                        &e.transform.rotation,
                        &s.truth.rotation
                    )
                    .to_degrees(),
                    (e.transform.translation.vector - s.truth.translation.vector).norm(),
                    e.diagnostics.threshold_m
                );
            }
            Err(e) => eprintln!("  err {e}"),
        }
    }
}

fn large_sweep() {
    let runs: u64 = std::env::var("RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    for f in [0.9, 0.98, 0.99] {
        for covariances in [false, true] {
            let spec = StereoSpec::street().with_n(20_000).with_outliers(f);
            let (mut ok, mut wrong, mut err) = (0, 0, 0);
            let mut ms = Vec::new();
            for seed in 0..runs {
                let s = spec.scenario(3000 + seed).unwrap();
                let data = if covariances {
                    s.data.clone()
                } else {
                    s.plain().unwrap()
                };
                let t0 = std::time::Instant::now();
                match PsoEstimator::default().estimate_seeded(&data, seed) {
                    Ok(e) if s.is_success(&e.transform) => ok += 1,
                    Ok(_) => wrong += 1,
                    Err(_) => err += 1,
                }
                ms.push(t0.elapsed().as_secs_f64() * 1e3);
            }
            ms.sort_by(f64::total_cmp);
            println!(
                "20000 rows {f:.2} cov={covariances}: {ok}/{runs} right, {wrong} wrong, {err} errors, median {:.1} ms",
                ms[ms.len() / 2]
            );
        }
    }
}

fn noisy_sweep() {
    use swarmpose_core::SvdEstimator;
    use swarmpose_core::geometry::rotation_angle_between;
    use swarmpose_sim::{OutlierMode, SceneSpec};
    let runs: u64 = std::env::var("RUNS")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(20);
    for noise in [0.02, 0.3, 1.0] {
        let (mut ok, mut wrong, mut err, mut ceiling, mut gross) = (0, 0, 0, 0, 0);
        for seed in 0..runs {
            let s = SceneSpec::default()
                .scenario(seed, noise, 0.8, OutlierMode::Random)
                .unwrap();
            let good = |p: &nalgebra::Isometry3<f64>| {
                rotation_angle_between(&p.rotation, &s.truth.rotation).to_degrees() < 2.0
                    && (p.translation.vector - s.truth.translation.vector).norm() < 0.2
            };
            match PsoEstimator::default().estimate_seeded(&s.data, seed) {
                Ok(e) if good(&e.transform) => ok += 1,
                Ok(e) => {
                    let r = rotation_angle_between(&e.transform.rotation, &s.truth.rotation);
                    let t = (e.transform.translation.vector - s.truth.translation.vector).norm();
                    wrong += 1;
                    gross += usize::from(r.to_degrees() > 5.0 || t > 1.0);
                }
                Err(_) => err += 1,
            }
            let idx: Vec<usize> = (0..s.inlier.len()).filter(|&i| s.inlier[i]).collect();
            ceiling += usize::from(
                SvdEstimator
                    .estimate_seeded(&s.data.select(&idx), 0)
                    .is_ok_and(|e| good(&e.transform)),
            );
        }
        println!(
            "noise {noise} m, 80 %: {ok}/{runs} right, {wrong} wrong ({gross} by > 5 deg or > 1 m), {err} errors; ceiling {ceiling}/{runs}"
        );
    }
}

fn write_timing_inputs() {
    let Ok(dir) = std::env::var("STEREO_OUT") else {
        return;
    };
    let dir = std::path::PathBuf::from(dir);
    for (n, f) in [(600, 0.9), (600, 0.97), (20_000, 0.9)] {
        let s = StereoSpec::street()
            .with_n(n)
            .with_outliers(f)
            .scenario(42)
            .unwrap();
        let name = format!("n{n}_o{f:.2}");
        swarmpose_data::correspondence_csv::write_path(
            dir.join(format!("{name}_cov.csv")),
            &s.data,
        )
        .unwrap();
        swarmpose_data::correspondence_csv::write_path(
            dir.join(format!("{name}_plain.csv")),
            &s.plain().unwrap(),
        )
        .unwrap();
    }
}

/// The measurement named by the first argument.
fn main() {
    let name = std::env::args().nth(1).unwrap_or_default();
    match name.as_str() {
        "sweep" => stereo_sweep(),
        "debug" => stereo_debug(),
        "large" => large_sweep(),
        "noisy" => noisy_sweep(),
        "timing-inputs" => write_timing_inputs(),
        _ => {
            eprintln!("usage: stereo_sweep sweep|debug|large|noisy|timing-inputs");
            std::process::exit(2);
        }
    }
}
