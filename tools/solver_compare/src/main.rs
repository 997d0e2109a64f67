//! Times swarmpose's sliding-window bundle adjustment against solver crates on the same
//! synthetic KITTI-sized window (see README.md).
//!
//! ```text
//! cargo run --release -- [--seed N] [--tracks N] [--outliers F] [--reps N] [--max-iterations N]
//! ```

#[cfg(feature = "apex")]
mod apex;
mod problem;
mod swarm;
mod tiny;

use std::time::Instant;

use nalgebra::Isometry3;

use problem::{KEYFRAMES, Problem, Spec, pose_error, robust_cost};

/// Command-line settings.
struct Args {
    spec: Spec,
    reps: usize,
    max_iterations: usize,
    /// Only the sweep of iteration counts (no timing).
    sweep: bool,
    /// Leave out tiny-solver to convergence (minutes).
    skip_tiny_converged: bool,
}

fn parse_args() -> Result<Args, String> {
    let mut args = Args {
        spec: Spec {
            seed: 1,
            tracks: 2000,
            outliers: 0.03,
        },
        reps: 10,
        max_iterations: 400,
        sweep: false,
        skip_tiny_converged: false,
    };
    let mut it = std::env::args().skip(1);
    while let Some(flag) = it.next() {
        if flag == "--sweep" {
            args.sweep = true;
            continue;
        }
        if flag == "--skip-tiny-converged" {
            args.skip_tiny_converged = true;
            continue;
        }
        let value = it.next().ok_or(format!("{flag} needs a value"))?;
        let bad = |e: &dyn std::fmt::Display| format!("{flag} {value}: {e}");
        match flag.as_str() {
            "--seed" => args.spec.seed = value.parse().map_err(|e| bad(&e))?,
            "--tracks" => args.spec.tracks = value.parse().map_err(|e| bad(&e))?,
            "--outliers" => args.spec.outliers = value.parse().map_err(|e| bad(&e))?,
            "--reps" => args.reps = value.parse().map_err(|e| bad(&e))?,
            "--max-iterations" => args.max_iterations = value.parse().map_err(|e| bad(&e))?,
            _ => return Err(format!("unknown flag {flag}")),
        }
    }
    if args.reps == 0 {
        return Err("--reps must be at least 1".into());
    }
    Ok(args)
}

/// One solver's figures.
pub(crate) struct Row {
    name: String,
    times_s: Vec<f64>,
    iterations: usize,
    /// Final robust cost, when the solver gives every pose and point.
    cost: Option<f64>,
    /// Error of the newest keyframe: metres, degrees.
    error: (f64, f64),
    /// The newest keyframe (camera in world).
    newest: Isometry3<f64>,
    note: String,
}

/// Median and 90th percentile (nearest rank) of `v`.
pub(crate) fn median_p90(v: &[f64]) -> (f64, f64) {
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let n = s.len();
    if n == 0 {
        return (f64::NAN, f64::NAN);
    }
    let median = if n % 2 == 1 {
        s[n / 2]
    } else {
        0.5 * (s[n / 2 - 1] + s[n / 2])
    };
    let rank = ((0.9 * n as f64).ceil() as usize).clamp(1, n);
    (median, s[rank - 1])
}

fn load() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .map(|s| s.split_whitespace().take(3).collect::<Vec<_>>().join(" "))
        .unwrap_or_else(|_| "unknown".into())
}

fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// swarmpose's window through `Window::add`, `max_iterations` per refinement.
fn run_swarmpose(
    p: &Problem,
    max_iterations: usize,
    reps: usize,
    label: &str,
) -> Result<Row, String> {
    let prepared = swarm::prepare(p, max_iterations)?;
    let solved = swarm::solve(p, &mut prepared.clone())?;
    let (tracks, obs) = (p.tracks.len(), p.observations());
    if solved.report.tracks != tracks || solved.report.observations != obs {
        return Err(format!(
            "the window refined {} tracks and {} measurements, the problem has {tracks} and {obs}",
            solved.report.tracks, solved.report.observations
        ));
    }
    let mut times_s = Vec::with_capacity(reps);
    for _ in 0..reps {
        let mut w = prepared.clone();
        let t = Instant::now();
        let s = swarm::solve(p, &mut w)?;
        times_s.push(t.elapsed().as_secs_f64());
        std::hint::black_box(s.pose);
    }
    let newest = solved.pose;
    // The window's own measurement agrees with the pose it gives out (keyframe 0 is the
    // world).
    let gap = pose_error(&newest, &solved.motion.motion).0;
    Ok(Row {
        name: format!("swarmpose window, {label}, 1 thread"),
        times_s,
        iterations: solved.report.iterations,
        cost: None,
        error: pose_error(&p.truth[KEYFRAMES - 1], &newest),
        newest,
        note: format!(
            "the whole last `Window::add` (linking, keyframe test, point pre-fit, LM); max_iterations {max_iterations}; window motion vs pose {gap:.1e} m"
        ),
    })
}

/// tiny-solver on `threads` rayon threads.
fn run_tiny(
    p: &Problem,
    max_iterations: usize,
    reps: usize,
    threads: usize,
    label: &str,
) -> Result<Row, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    let run = || {
        pool.install(|| tiny::solve(p, max_iterations))
            .ok_or("tiny-solver failed")
    };
    let solved = run()?;
    let mut times_s = Vec::with_capacity(reps);
    let mut build_s = Vec::with_capacity(reps);
    for _ in 0..reps {
        let t = Instant::now();
        let s = run()?;
        times_s.push(t.elapsed().as_secs_f64());
        build_s.push(s.build_s);
    }
    let newest = problem::pose_wc(&solved.poses[KEYFRAMES - 1]);
    Ok(Row {
        name: format!("tiny-solver 0.18.8, {label}, {threads} thread(s)"),
        times_s,
        iterations: solved.iterations,
        cost: Some(robust_cost(p, &solved.poses, &solved.points)),
        error: pose_error(&p.truth[KEYFRAMES - 1], &newest),
        newest,
        note: format!(
            "problem construction + optimize (construction median {:.3} s); max_iteration {max_iterations}",
            median_p90(&build_s).0
        ),
    })
}

fn main() {
    if let Err(e) = run() {
        eprintln!("solver_compare: {e}");
        std::process::exit(1);
    }
}

fn run() -> Result<(), String> {
    let args = parse_args()?;
    let load_before = load();
    let p = Problem::generate(&args.spec);
    let cores = std::thread::available_parallelism().map_or(0, |n| n.get());
    println!("# solver_compare");
    println!();
    println!(
        "machine: {} x86_64 core(s) available, {}; load average (1, 5, 15 min) before: {load_before}",
        cores,
        cpu_model()
    );
    println!(
        "problem: seed {}, {KEYFRAMES} keyframes, {} tracks, {} stereo measurements ({} gross outliers, {:.1} %), {} repetitions",
        args.spec.seed,
        p.tracks.len(),
        p.observations(),
        p.outliers,
        100.0 * p.outliers as f64 / p.observations() as f64,
        args.reps
    );
    let poses0: Vec<_> = p.initial.iter().map(problem::pose_cw).collect();
    let (e0t, e0r) = pose_error(&p.truth[KEYFRAMES - 1], &p.initial[KEYFRAMES - 1]);
    println!(
        "initial: robust cost {:.1}, newest keyframe off by {e0t:.4} m, {e0r:.4} deg",
        robust_cost(&p, &poses0, &p.initial_points())
    );
    let truth: Vec<_> = p.truth.iter().map(problem::pose_cw).collect();
    println!(
        "(robust cost at the true poses with the initial points: {:.1})",
        robust_cost(&p, &truth, &p.initial_points())
    );
    println!();
    if args.sweep {
        return sweep(&p);
    }
    let n = args.max_iterations;
    // Converged: the iteration limit only as a guard; the solvers stop on a relative
    // decrease of the cost below 1e-6.
    let conv = format!("converged (limit {n})");
    let mut rows = vec![
        run_swarmpose(&p, n, args.reps, &conv)?,
        run_swarmpose(&p, 10, args.reps, "10 iterations")?,
        run_swarmpose(&p, 1, args.reps, "1 iteration (engine default)")?,
        // No iteration: what `add` costs around the solver (linking, the keyframe test,
        // gathering the tracks, the points' pre-fit).
        run_swarmpose(&p, 0, args.reps, "0 iterations (no LM step)")?,
    ];
    #[cfg(feature = "apex")]
    {
        rows.push(apex::run(&p, n, args.reps, 1, &conv)?);
        rows.push(apex::run(&p, 9, args.reps, 1, "10 iterations")?);
        rows.push(apex::run(&p, 9, args.reps, 2, "10 iterations")?);
        rows.push(apex::run(&p, 0, args.reps, 1, "1 iteration")?);
    }
    rows.push(run_tiny(&p, 10, args.reps, 1, "10 iterations")?);
    rows.push(run_tiny(&p, 10, args.reps, 2, "10 iterations")?);
    rows.push(run_tiny(&p, 1, args.reps, 1, "1 iteration")?);
    if !args.skip_tiny_converged {
        rows.push(run_tiny(&p, n, args.reps, 1, &conv)?);
    }
    let reference = rows[0].newest;
    println!(
        "| solver | median s | p90 s | iterations | final robust cost | newest: error m | error deg | vs swarmpose (converged) m |"
    );
    println!("|---|---|---|---|---|---|---|---|");
    for r in &mut rows {
        let (med, p90) = median_p90(&r.times_s);
        let cost = r.cost.map_or("n/a".to_string(), |c| format!("{c:.2}"));
        let vs = pose_error(&reference, &r.newest).0;
        println!(
            "| {} | {med:.4} | {p90:.4} | {} | {cost} | {:.5} | {:.5} | {vs:.1e} |",
            r.name, r.iterations, r.error.0, r.error.1
        );
    }
    println!();
    for r in &rows {
        println!("* {}: {}", r.name, r.note);
    }
    println!();
    println!("load average after: {}", load());
    Ok(())
}

/// The newest keyframe's error and the final cost against the iteration limit (one run
/// each, no timing).
fn sweep(p: &Problem) -> Result<(), String> {
    println!(
        "| max iterations | swarmpose: iterations | error m | error deg | tiny-solver: iterations | cost | error m | apex-solver: iterations | cost | error m |"
    );
    println!("|---|---|---|---|---|---|---|---|---|---|");
    for n in [1, 2, 3, 5, 10, 20, 50, 100, 200, 400] {
        let s = run_swarmpose(p, n, 1, "sweep")?;
        let t = if n <= 50 {
            let t = run_tiny(p, n, 0, 2, "sweep")?;
            format!(
                "{} | {:.2} | {:.6}",
                t.iterations,
                t.cost.unwrap_or(f64::NAN),
                t.error.0
            )
        } else {
            "- | - | -".to_string()
        };
        #[cfg(feature = "apex")]
        let a = {
            let a = apex::run(p, n - 1, 0, 2, "sweep")?;
            format!(
                "{} | {:.2} | {:.6}",
                a.iterations,
                a.cost.unwrap_or(f64::NAN),
                a.error.0
            )
        };
        #[cfg(not(feature = "apex"))]
        let a = "- | - | -".to_string();
        println!(
            "| {n} | {} | {:.6} | {:.6} | {t} | {a} |",
            s.iterations, s.error.0, s.error.1
        );
    }
    Ok(())
}
