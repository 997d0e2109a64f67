//! Shared helpers of the odometry tests.
#![allow(dead_code)]

use std::path::PathBuf;
use std::sync::{Arc, Mutex, OnceLock};

use nalgebra::{Isometry3, Vector6};
use swarmpose_datasets::open;
use swarmpose_eval::associate::by_index;
use swarmpose_eval::{Evaluation, Trajectory, evaluate};
use swarmpose_odometry::{Decision, FrameResult, Odometry, OdometryConfig, Status};
use swarmpose_runs::batch::{camera_of, collect};

/// The directory of a shared data set (see [`swarmpose_testdata::dataset_for_test`]).
pub fn dataset(name: &str) -> Option<PathBuf> {
    swarmpose_testdata::dataset_for_test(name)
}

/// A finished run: every frame's result and the final calibration decision.
pub struct Run {
    pub results: Vec<FrameResult>,
    pub calibration: Decision,
}

impl Run {
    pub fn poses(&self) -> Vec<Isometry3<f64>> {
        self.results.iter().map(|r| r.pose).collect()
    }

    /// Frames after the first whose motion was not tracked.
    pub fn untracked(&self) -> usize {
        self.results
            .iter()
            .filter(|r| !matches!(r.status, Status::First | Status::Tracked))
            .count()
    }
}

/// The default engine over a sequence.
pub fn run_sequence(seq: &dyn swarmpose_datasets::StereoSequence, config: OdometryConfig) -> Run {
    let mut odo = Odometry::new(camera_of(seq), config).expect("engine");
    let results = collect(seq, &mut odo, 0.1).expect("odometry");
    Run {
        results,
        calibration: odo.calibration(),
    }
}

/// The default run on a shared data set.
pub fn default_run(name: &str) -> Option<Arc<Run>> {
    shared_run(name, OdometryConfig::default())
}

/// The run of `config` on the shared data set `name`, computed once for all the tests of
/// this binary that ask for it (the engine is deterministic: the same sequence and
/// settings give the same results, `two_threads.rs`). A test asking while another
/// computes it waits for that run.
pub fn shared_run(name: &str, config: OdometryConfig) -> Option<Arc<Run>> {
    type Cell = Arc<OnceLock<Arc<Run>>>;
    static RUNS: OnceLock<Mutex<Vec<(String, OdometryConfig, Cell)>>> = OnceLock::new();
    let dir = dataset(name)?;
    let cell = {
        let mut runs = RUNS
            .get_or_init(Mutex::default)
            .lock()
            .unwrap_or_else(std::sync::PoisonError::into_inner);
        match runs.iter().find(|(n, c, _)| n == name && *c == config) {
            Some((_, _, cell)) => Arc::clone(cell),
            None => {
                let cell = Cell::default();
                runs.push((name.to_owned(), config.clone(), Arc::clone(&cell)));
                cell
            }
        }
    };
    Some(Arc::clone(cell.get_or_init(|| {
        let seq = open(&dir).expect("open");
        Arc::new(run_sequence(seq.as_ref(), config))
    })))
}

/// Evaluation of poses against ground truth of the same frames.
pub fn evaluate_poses(poses: Vec<Isometry3<f64>>, gt: &[Isometry3<f64>]) -> Evaluation {
    let pairs = by_index(
        &Trajectory::indexed("estimate", poses),
        &Trajectory::indexed("ground truth", gt.to_vec()),
    )
    .expect("same length");
    evaluate(&pairs).expect("evaluate")
}

/// Evaluation of a run against the sequence's camera ground truth.
pub fn evaluate_run(name: &str, r: &Run) -> Evaluation {
    let dir = dataset(name).expect("present");
    let seq = open(&dir).expect("open");
    evaluate_poses(r.poses(), seq.ground_truth().expect("ground truth"))
}

/// Feeds frames `0..n` of a synthetic feature stream to `tracker`, calling `each` with
/// every result.
pub fn stream(
    seq: &swarmpose_runs::synthetic::features::FeatureSequence,
    tracker: &mut swarmpose_odometry::tracker::Tracker<
        swarmpose_vision::features::BinaryDescriptor,
    >,
    n: usize,
    mut each: impl FnMut(usize, &FrameResult),
) {
    for k in 0..n {
        let r = tracker
            .track(
                seq.frame(k),
                None,
                seq.timestamp_s(k),
                swarmpose_odometry::StageTimes::default(),
            )
            .expect("frame");
        each(k, &r);
    }
}

/// The error `ξ = (ν, ω)` of `estimate` with `truth = estimate ∘ E(ξ)`.
pub fn motion_error(estimate: &Isometry3<f64>, truth: &Isometry3<f64>) -> Vector6<f64> {
    let r = estimate.rotation.inverse() * truth.rotation;
    let nu = estimate.rotation.inverse() * (truth.translation.vector - estimate.translation.vector);
    let w = r.scaled_axis();
    Vector6::new(nu.x, nu.y, nu.z, w.x, w.y, w.z)
}

/// ATE of a run on the Karlsruhe sequence in `dir` after the SE(3) Umeyama alignment of
/// its camera positions onto the INS positions, percent of the INS path length.
pub fn karlsruhe_ate_percent(dir: &std::path::Path, r: &Run) -> f64 {
    karlsruhe_errors_percent(dir, r).0
}

/// The ATE and the final position error of a run on the Karlsruhe sequence in `dir` after
/// the SE(3) Umeyama alignment of its camera positions onto the INS positions, percent of
/// the INS path length (as `swarmpose odometry` prints them).
pub fn karlsruhe_errors_percent(dir: &std::path::Path, r: &Run) -> (f64, f64) {
    use nalgebra::Point3;
    let ins = swarmpose_datasets::karlsruhe::KarlsruheSequence::open(dir)
        .expect("open")
        .ins_positions()
        .expect("insdata.txt")
        .expect("INS positions");
    assert_eq!(r.results.len(), ins.len());
    let x: Vec<Point3<f64>> = r
        .poses()
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    let y: Vec<Point3<f64>> = ins.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect();
    let t = swarmpose_eval::metrics::umeyama(&x, &y).expect("align");
    let sq: f64 = x
        .iter()
        .zip(&y)
        .map(|(a, b)| (b - t * a).norm_squared())
        .sum();
    let length: f64 = y.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let last = x.len() - 1;
    (
        100.0 * (sq / x.len() as f64).sqrt() / length,
        100.0 * (y[last] - t * x[last]).norm() / length,
    )
}

/// Issue 30's bar on an online step at a change of the calibration's model: 1 %.
pub const CALIBRATION_STEP_BAR: f64 = 0.01;

/// Per frame `k ≥ 1`: whether the correction model changed there (frame `k`'s differs from
/// frame `k − 1`'s or frame `k + 1`'s, as `tools/variants/step_ratios.py` marks it), and
/// the online step length `|t_k − t_{k−1}|` (positions of [`FrameResult::pose`], as given
/// out) over the smoothed trajectory's step between the same two frames (each frame's last
/// pose in the window, [`swarmpose_runs::output::Smoothed`]), minus one. Steps shorter than
/// 1 % of the median online step are left out (their ratio says nothing).
pub fn online_against_smoothed(r: &Run) -> Vec<(usize, bool, f64)> {
    let mut smoothed = swarmpose_runs::output::Smoothed::default();
    for f in &r.results {
        smoothed.add(f);
    }
    let step = |p: &[Isometry3<f64>], k: usize| {
        (p[k].translation.vector - p[k - 1].translation.vector).norm()
    };
    let online = r.poses();
    let s = smoothed.poses();
    let mut lengths: Vec<f64> = (1..online.len()).map(|k| step(&online, k)).collect();
    lengths.sort_by(f64::total_cmp);
    let floor = 0.01 * lengths.get(lengths.len() / 2).copied().unwrap_or(0.0);
    let m: Vec<_> = r.results.iter().map(|f| f.correction_model).collect();
    (1..online.len())
        .filter(|&k| step(&online, k) > floor && step(s, k) > floor)
        .map(|k| {
            let changed = m[k] != m[k - 1] || m.get(k + 1).is_some_and(|n| *n != m[k]);
            (k, changed, step(&online, k) / step(s, k) - 1.0)
        })
        .collect()
}

/// The worst `|online / smoothed − 1|` of [`online_against_smoothed`] at the frames where
/// the model changed and at the others (0 when there is none), and how many changed.
pub fn worst_steps(r: &Run) -> (f64, f64, usize) {
    let rows = online_against_smoothed(r);
    let worst = |changed: bool| {
        rows.iter()
            .filter(|x| x.1 == changed)
            .fold(0.0, |w: f64, x| {
                if x.2.is_nan() {
                    f64::NAN
                } else {
                    w.max(x.2.abs())
                }
            })
    };
    let n = rows.iter().filter(|x| x.1).count();
    (worst(true), worst(false), n)
}
