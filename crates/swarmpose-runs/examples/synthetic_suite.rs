//! The engine on a suite of rendered synthetic stereo sequences (speeds, turns to either
//! side): final drift, RMS eq. (20) and aligned ATE for each window size given
//! on the command line (0: frame to frame), so that a change to the window is judged on
//! more than one sequence. Slow (every frame is rendered): not a test. A window size may
//! end in `f` or `a` to marginalise the keyframe that leaves the window
//! (`Marginalisation::Finished` or `All`; without, its information is discarded).
//!
//! ```sh
//! cargo run --release -p swarmpose-runs --example synthetic_suite -- 0 10 20 10f 10a
//! ```

use swarmpose_datasets::StereoSequence;
use swarmpose_eval::associate::by_index;
use swarmpose_eval::{Trajectory, evaluate};
use swarmpose_odometry::window::Marginalisation;
use swarmpose_odometry::{Odometry, OdometryConfig, Status};
use swarmpose_runs::batch::{camera_of, collect};
use swarmpose_runs::synthetic::SyntheticSequence;

fn main() {
    let windows: Vec<String> = std::env::args().skip(1).collect();
    let windows = if windows.is_empty() {
        vec!["0".to_string(), "10".to_string()]
    } else {
        windows
    };
    // (frames, metres per frame, yaw per frame in degrees): paths that stay inside the
    // rendered street (house fronts 5 m left and 6 m right, a far wall 45 m ahead).
    let suite = [
        (36, 1.0, 0.0),
        (36, 1.0, 0.3),
        (50, 0.5, -0.3),
        (60, 0.3, 0.4),
        (40, 0.2, 1.0),
        (24, 1.5, -0.2),
        // A robot creeping (or a camera at 10 times the frame rate).
        (60, 0.05, 0.0),
    ];
    println!("| sequence | window | final drift | RMS eq. (20) | ATE aligned | untracked |");
    println!("|---|---|---|---|---|---|");
    let mut sums = vec![(0.0, 0.0, 0.0); windows.len()];
    for &(n, step, yaw_deg) in &suite {
        let seq = SyntheticSequence::new(n, step, f64::to_radians(yaw_deg));
        let gt = seq.ground_truth().expect("ground truth").to_vec();
        for (w, sum) in windows.iter().zip(&mut sums) {
            let (size, mode) = match w.strip_suffix('f') {
                Some(k) => (k, Marginalisation::Finished),
                None => match w.strip_suffix('a') {
                    Some(k) => (k, Marginalisation::All),
                    None => (w.as_str(), Marginalisation::Off),
                },
            };
            let size: usize = size
                .parse()
                .expect("window sizes: integers, optionally ending in f or a");
            let config = OdometryConfig::default()
                .with_window(size)
                .with_marginalisation(mode);
            let mut odo = Odometry::new(camera_of(&seq), config).expect("engine");
            let results = collect(&seq, &mut odo, 0.1).expect("odometry");
            let poses: Vec<_> = results.iter().map(|r| r.pose).collect();
            let e = evaluate(
                &by_index(
                    &Trajectory::indexed("estimate", poses),
                    &Trajectory::indexed("truth", gt.clone()),
                )
                .expect("pairs"),
            )
            .expect("evaluate");
            let drift = e.final_drift_percent.unwrap_or(f64::NAN);
            let untracked = results
                .iter()
                .filter(|r| !matches!(r.status, Status::First | Status::Tracked))
                .count();
            println!(
                "| {n} frames, {step} m, {yaw_deg} deg | {w} | {drift:.3} % | {:.5} | {:.4} m | {untracked} |",
                e.eq20_rms, e.ate_aligned.rmse
            );
            sum.0 += drift / suite.len() as f64;
            sum.1 += e.eq20_rms / suite.len() as f64;
            sum.2 += e.ate_aligned.rmse / suite.len() as f64;
        }
    }
    for (w, s) in windows.iter().zip(&sums) {
        println!(
            "| mean | {w} | {:.3} % | {:.5} | {:.4} m | |",
            s.0, s.1, s.2
        );
    }
}
