//! The split-feature NEES ([`swarmpose_odometry::refine::split`]) of the rendered synthetic
//! street (the built-in sequence of `swarmpose odometry` with no path) over other draws of
//! its textures, and over longer paths: is the figure of the 20-frame street a bias of the
//! covariance or the sampling noise of a short mean? Each run is frame to frame with the
//! split check and the systematic floor (the default configuration); one line per run
//! (mean with the floor held out, median, the model's alone, pairs, pairs of 30 or more),
//! then the distribution of the runs' means. Slow (every frame is rendered): not a test.
//!
//! ```sh
//! # 40 textures of the 20-frame street (0.6 m and 1 degree a frame), per-frame rows too:
//! cargo run --release -p swarmpose-runs --example street_split_nees -- \
//!     --seeds 0..40 --frames 20 --step 0.6 --yaw 1 [--per-frame FILE.csv]
//! ```

use std::io::Write;
use std::ops::ControlFlow;

use swarmpose_odometry::{Odometry, OdometryConfig};
use swarmpose_runs::batch::{camera_of, run_sequence};
use swarmpose_runs::synthetic::SyntheticSequence;

/// The command line: seeds `a..b`, frames, metres and degrees a frame, per-frame CSV.
struct Args {
    seeds: std::ops::Range<u64>,
    frames: usize,
    step_m: f64,
    yaw_deg: f64,
    per_frame: Option<String>,
}

fn args() -> Result<Args, String> {
    let mut a = Args {
        seeds: 0..10,
        frames: 20,
        step_m: 0.6,
        yaw_deg: 1.0,
        per_frame: None,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let bad = |e: &dyn std::fmt::Display| format!("{flag} {value}: {e}");
        match flag.as_str() {
            "--seeds" => {
                let (lo, hi) = value.split_once("..").ok_or("--seeds A..B")?;
                a.seeds = lo.parse().map_err(|e| bad(&e))?..hi.parse().map_err(|e| bad(&e))?;
            }
            "--frames" => a.frames = value.parse().map_err(|e| bad(&e))?,
            "--step" => a.step_m = value.parse().map_err(|e| bad(&e))?,
            "--yaw" => a.yaw_deg = value.parse().map_err(|e| bad(&e))?,
            "--per-frame" => a.per_frame = Some(value),
            _ => return Err(format!("unknown argument {flag}")),
        }
    }
    Ok(a)
}

/// Mean, median of `x`.
fn mean_median(x: &[f64]) -> (f64, f64) {
    let mut s = x.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    let median = if n % 2 == 1 {
        s[n / 2]
    } else {
        (s[n / 2 - 1] + s[n / 2]) / 2.0
    };
    (s.iter().sum::<f64>() / n as f64, median)
}

fn main() {
    let a = match args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("street_split_nees: {e}");
            std::process::exit(2);
        }
    };
    let mut csv = a.per_frame.as_ref().map(|p| {
        let mut f = std::fs::File::create(p).expect("per-frame CSV");
        writeln!(
            f,
            "seed,frame,nees,model_nees,inliers_left,inliers_right,\
             z_nu_x,z_nu_y,z_nu_z,z_omega_x,z_omega_y,z_omega_z"
        )
        .expect("write");
        f
    });
    println!(
        "street: {} frames, {} m and {} deg a frame, frame to frame, default configuration",
        a.frames, a.step_m, a.yaw_deg
    );
    println!("| seed | pairs | mean NEES | median | model's alone | pairs of 30+ |");
    println!("|---:|---:|---:|---:|---:|---:|");
    let mut means = Vec::new();
    let (mut all, mut all_model) = (Vec::new(), Vec::new());
    for seed in a.seeds.clone() {
        let seq = SyntheticSequence::new(a.frames, a.step_m, a.yaw_deg.to_radians())
            .with_texture_seed(seed);
        let config = OdometryConfig {
            split_check: true,
            ..OdometryConfig::default()
        }
        .with_window(0);
        let mut odo = Odometry::new(camera_of(&seq), config).expect("engine");
        let (mut nees, mut model) = (Vec::new(), Vec::new());
        run_sequence(&seq, &mut odo, 0.1, &mut |r| {
            if let Some(s) = r.split {
                nees.push(s.nees);
                model.push(s.model_nees);
                if let Some(f) = csv.as_mut() {
                    // Each axis's difference in its own standard deviations (the floor's).
                    let z: Vec<String> = (0..6)
                        .map(|i| format!("{:.3}", s.difference[i] / s.covariance[(i, i)].sqrt()))
                        .collect();
                    writeln!(
                        f,
                        "{seed},{},{:.4},{:.4},{},{},{}",
                        r.index,
                        s.nees,
                        s.model_nees,
                        s.inliers[0],
                        s.inliers[1],
                        z.join(",")
                    )
                    .expect("write");
                }
            }
            ControlFlow::Continue(())
        })
        .expect("odometry");
        if nees.is_empty() {
            println!("| {seed} | 0 | — | — | — | — |");
            continue;
        }
        let (mean, median) = mean_median(&nees);
        let big = nees.iter().filter(|&&x| x >= 30.0).count();
        println!(
            "| {seed} | {} | {mean:.2} | {median:.2} | {:.2} | {big} |",
            nees.len(),
            mean_median(&model).0
        );
        means.push(mean);
        all.extend(nees);
        all_model.extend(model);
    }
    if means.len() > 1 {
        let (m, med) = mean_median(&means);
        let sd =
            (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (means.len() - 1) as f64).sqrt();
        let mut s = means.clone();
        s.sort_by(f64::total_cmp);
        let inside = means.iter().filter(|x| (4.5..=7.5).contains(*x)).count();
        let (pooled, pooled_median) = mean_median(&all);
        let (model, model_median) = mean_median(&all_model);
        // The 95th percentile of χ² with 6 degrees of freedom: 5 % of honest pairs exceed it.
        let above =
            |x: &[f64]| 100.0 * x.iter().filter(|&&v| v > 12.592).count() as f64 / x.len() as f64;
        println!(
            "\n{} runs: mean of the means {m:.2} (sd {sd:.2}, median {med:.2}, range {:.2}-{:.2}), \
             {inside} within [4.5, 7.5]; all {} pairs pooled: mean {pooled:.2}, median \
             {pooled_median:.2}, {} of 30 or more, {:.1} % above 12.59 (χ²₆'s 95th percentile); \
             the model's alone: mean {model:.2}, median {model_median:.2}, {:.1} % above 12.59",
            means.len(),
            s[0],
            s[s.len() - 1],
            all.len(),
            all.iter().filter(|&&x| x >= 30.0).count(),
            above(&all),
            above(&all_model)
        );
    }
}
