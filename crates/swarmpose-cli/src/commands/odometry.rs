//! `swarmpose odometry [SEQUENCE_DIR] [--method ...] [--detector ...] [--out DIR]`:
//! stereo visual odometry over a sequence: for every consecutive pair the front end,
//! the estimator and the chaining of eq. (2); writes the trajectory (KITTI and TUM),
//! a per-frame log and the plots of figure 17, and evaluates against the ground truth
//! when the sequence has one.

use std::path::PathBuf;

use clap::{Args, ValueEnum};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use nalgebra::Isometry3;
use swarmpose_datasets::{StereoSequence, open};
use swarmpose_odometry::output::{evaluate_run, write_text_outputs};
use swarmpose_odometry::plots::write_plots;
use swarmpose_odometry::synthetic::SyntheticSequence;
use swarmpose_odometry::{DisparityOffset, OdometryConfig, OdometryError, OdometryRun, run};
use swarmpose_vision::frontend::{DisparityCorrection, Frontend};

/// The disparity correction self-calibrated from the images.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum DisparityModel {
    /// Offset plus a term quadratic in the image column (a yaw of the right camera).
    Quadratic,
    /// A constant offset.
    Constant,
}

use crate::commands::correspondences::Detector;
use crate::error::CliError;
use crate::methods::{EstimatorOptions, Method, build};

/// Arguments of `swarmpose odometry`.
#[derive(Debug, Args)]
#[command(after_help = "\
SEQUENCE_DIR is a KITTI odometry sequence, a Karlsruhe sequence or a EuRoC MAV sequence \
(see `swarmpose correspondences --help`). Outputs in --out: trajectory.kitti.txt (KITTI \
poses), trajectory.tum.txt (timestamp tx ty tz qx qy qz qw; timestamps = frame index x \
--frame-period), frames.csv (per frame: status, features, stereo points, matches, \
inliers, time per stage in ms, the motion from the previous frame and the position), \
trajectory.png/.svg (top view, x right, z forward, against the ground truth: figure 17) \
and, with ground truth, errors.png (per-frame eq. (20) and RPE), groundtruth.kitti.txt, \
groundtruth.tum.txt and evaluation.json (as `swarmpose evaluate --json`).

A pair the estimator cannot solve (matching fails, too few inliers) repeats the previous \
motion (constant velocity); frames.csv marks it `constant-velocity (REASON)` and the \
summary counts it; never a silent identity.

Exit status: 0 on success; 2 for bad options or an unreadable, malformed or too short \
sequence; 1 when an output cannot be written.")]
pub struct OdometryArgs {
    /// Sequence directory; without it, the built-in synthetic stereo sequence.
    #[arg(value_name = "SEQUENCE_DIR")]
    pub sequence: Option<PathBuf>,

    /// Estimator.
    #[arg(long, value_enum, default_value_t = Method::Pso)]
    pub method: Method,

    /// Detector and descriptor.
    #[arg(long, value_enum, default_value_t = Detector::Orb)]
    pub detector: Detector,

    /// Output directory (created if needed).
    #[arg(long, value_name = "DIR", default_value = "out/odometry")]
    pub out: PathBuf,

    /// Seed of the estimator (pair k uses seed + k).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,

    /// Fixed disparity offset, pixels, instead of self-calibrating the correction from the
    /// images (with --disparity-quadratic: the offset at the image centre).
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    pub disparity_offset: Option<f64>,

    /// Fixed quadratic term of the disparity correction, pixels per unit x² with
    /// x = (u - cx) / f (a yaw of the right camera); with --disparity-offset (default 0).
    #[arg(long, value_name = "PX", allow_negative_numbers = true)]
    pub disparity_quadratic: Option<f64>,

    /// Disparity correction to self-calibrate when none is fixed: `quadratic`
    /// (offset + quadratic x², a yaw of the right camera) or `constant` (offset only).
    #[arg(long, value_enum, default_value_t = DisparityModel::Quadratic)]
    pub disparity_model: DisparityModel,

    /// Keep the estimator's motion: no Mahalanobis refinement on the stereo covariances.
    #[arg(long)]
    pub no_refine: bool,

    /// Fewest inliers for a motion to be accepted.
    #[arg(long, value_name = "N", default_value_t = OdometryConfig::default().min_inliers)]
    pub min_inliers: usize,

    /// Seconds between frames (timestamps of the TUM output).
    #[arg(long, value_name = "S", default_value_t = OdometryConfig::default().frame_period_s)]
    pub frame_period: f64,

    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,

    #[command(flatten)]
    pub options: EstimatorOptions,
}

fn odometry_error(e: OdometryError) -> CliError {
    if e.is_input() {
        CliError::usage(e.to_string())
    } else {
        CliError::failure(e.to_string())
    }
}

fn progress_bar(quiet: bool) -> ProgressBar {
    let pb = ProgressBar::new(0);
    if quiet {
        pb.set_draw_target(ProgressDrawTarget::hidden());
    }
    if let Ok(style) =
        ProgressStyle::with_template("{prefix} [{bar:40}] {pos}/{len} frames {per_sec} eta {eta}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb
}

/// Runs the pipeline on `seq` with the chosen detector.
fn run_sequence(
    seq: &dyn StereoSequence,
    args: &OdometryArgs,
    config: &OdometryConfig,
) -> Result<OdometryRun, CliError> {
    let estimator = build(args.method, &args.options)?;
    let pb = progress_bar(args.quiet);
    pb.set_prefix("odometry");
    let mut progress = |done: usize, total: usize| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    };
    let rig = seq.calibration();
    let r = match args.detector {
        Detector::Orb => run(
            seq,
            &Frontend::orb(rig),
            estimator.as_ref(),
            config,
            &mut progress,
        ),
        Detector::Surf => run(
            seq,
            &Frontend::surf(rig),
            estimator.as_ref(),
            config,
            &mut progress,
        ),
    };
    pb.finish_and_clear();
    r.map_err(odometry_error)
}

/// Runs `odometry`.
///
/// # Errors
/// Bad options or sequence (exit 2), unwritable outputs (exit 1).
pub fn run_command(args: &OdometryArgs) -> Result<(), CliError> {
    if !(args.frame_period.is_finite() && args.frame_period > 0.0) {
        return Err(CliError::usage(
            "--frame-period must be a positive number of seconds",
        ));
    }
    for (flag, v) in [
        ("--disparity-offset", args.disparity_offset),
        ("--disparity-quadratic", args.disparity_quadratic),
    ] {
        if v.is_some_and(|d| !d.is_finite()) {
            return Err(CliError::usage(format!(
                "{flag} must be a finite number of pixels"
            )));
        }
    }
    let disparity_offset = match (args.disparity_offset, args.disparity_quadratic) {
        (None, None) => match args.disparity_model {
            DisparityModel::Quadratic => DisparityOffset::SelfCalibrate,
            DisparityModel::Constant => DisparityOffset::SelfCalibrateConstant,
        },
        (offset, quadratic) => DisparityOffset::Correction(DisparityCorrection {
            offset_px: offset.unwrap_or(0.0),
            quadratic_px: quadratic.unwrap_or(0.0),
        }),
    };
    let config = OdometryConfig {
        refine: !args.no_refine,
        disparity_offset,
        min_inliers: args.min_inliers.max(3),
        seed: args.seed,
        frame_period_s: args.frame_period,
    };
    let Some(dir) = &args.sequence else {
        // No data: the built-in synthetic street, rendered along a known path.
        let seq = SyntheticSequence::default();
        eprintln!(
            "swarmpose: no SEQUENCE_DIR: running on the built-in synthetic stereo sequence \
             ({} frames rendered from a textured street along a known path)",
            seq.len()
        );
        let r = run_sequence(&seq, args, &config)?;
        return finish(&r, "built-in synthetic sequence", seq.ground_truth(), args);
    };
    if swarmpose_odometry::rgbd::detect(dir) {
        return run_rgbd_command(dir, args, &config);
    }
    let seq = open(dir).map_err(|e| CliError::usage(e.to_string()))?;
    if seq.len() < 2 {
        return Err(CliError::usage(format!(
            "{}: {} frame(s): odometry needs at least 2",
            dir.display(),
            seq.len()
        )));
    }
    let title = format!("{} ({})", dir.display(), seq.layout());
    let r = run_sequence(seq.as_ref(), args, &config)?;
    let gt: Option<Vec<Isometry3<f64>>> = seq.ground_truth().map(<[_]>::to_vec);
    finish(&r, &title, gt.as_deref(), args)?;
    if seq.layout() == "karlsruhe" {
        ins_summary(dir, &r);
    }
    Ok(())
}

/// A TUM RGB-D directory (`rgb.txt`, `depth.txt`).
fn run_rgbd_command(
    dir: &std::path::Path,
    args: &OdometryArgs,
    config: &OdometryConfig,
) -> Result<(), CliError> {
    use swarmpose_odometry::rgbd::{RgbdSequence, run_rgbd};
    use swarmpose_vision::stereo::RectifiedStereo;
    if args.detector != Detector::Orb {
        return Err(CliError::usage(
            "--detector surf is not available for RGB-D input (use orb)",
        ));
    }
    if args.disparity_offset.is_some() || args.disparity_quadratic.is_some() {
        return Err(CliError::usage(
            "--disparity-offset and --disparity-quadratic do not apply to RGB-D input",
        ));
    }
    let seq = RgbdSequence::open(dir).map_err(odometry_error)?;
    if seq.len() < 2 {
        return Err(CliError::usage(format!(
            "{}: {} frame(s): odometry needs at least 2",
            dir.display(),
            seq.len()
        )));
    }
    let k = seq.intrinsics();
    let rig = RectifiedStereo {
        fx: k.fx,
        fy: k.fy,
        cx: k.cx,
        cy: k.cy,
        baseline_m: 0.075,
    };
    let estimator = build(args.method, &args.options)?;
    let pb = progress_bar(args.quiet);
    pb.set_prefix("odometry (RGB-D)");
    let r = run_rgbd(
        &seq,
        &Frontend::orb(rig),
        estimator.as_ref(),
        config,
        &mut |done, total| {
            pb.set_length(total as u64);
            pb.set_position(done as u64);
        },
    );
    pb.finish_and_clear();
    let r = r.map_err(odometry_error)?;
    let title = format!("{} (TUM RGB-D)", dir.display());
    finish(&r, &title, seq.ground_truth(), args)
}

/// Karlsruhe has no camera ground truth, only rough INS positions of the vehicle in
/// another frame: the ATE of our positions after their SE(3) Umeyama alignment.
fn ins_summary(dir: &std::path::Path, r: &OdometryRun) {
    use nalgebra::Point3;
    let ins =
        swarmpose_datasets::karlsruhe::KarlsruheSequence::open(dir).and_then(|k| k.ins_positions());
    let Ok(Some(ins)) = ins else {
        return;
    };
    if ins.len() != r.poses.len() {
        return;
    }
    let x: Vec<Point3<f64>> = r
        .poses
        .iter()
        .map(|p| Point3::from(p.translation.vector))
        .collect();
    let y: Vec<Point3<f64>> = ins.iter().map(|p| Point3::new(p[0], p[1], p[2])).collect();
    let Ok(t) = swarmpose_eval::metrics::umeyama(&x, &y) else {
        return;
    };
    let ate: Vec<f64> = x.iter().zip(&y).map(|(a, b)| (b - t * a).norm()).collect();
    let stats = swarmpose_eval::Stats::of(&ate);
    let length: f64 = y.windows(2).map(|w| (w[1] - w[0]).norm()).sum();
    let last = ate.last().copied().unwrap_or(0.0);
    println!(
        "vs INS positions (insdata.txt, after SE(3) alignment): path {length:.2} m, ATE {:.3} m ({:.2} % of the path), final position error {last:.3} m ({:.2} %)",
        stats.rmse,
        100.0 * stats.rmse / length.max(1e-9),
        100.0 * last / length.max(1e-9)
    );
}

/// Writes the outputs and prints the summary.
fn finish(
    r: &OdometryRun,
    title: &str,
    gt: Option<&[Isometry3<f64>]>,
    args: &OdometryArgs,
) -> Result<(), CliError> {
    let evaluation = match gt {
        Some(g) if g.len() == r.poses.len() => Some(evaluate_run(r, g).map_err(odometry_error)?),
        Some(g) => {
            eprintln!(
                "swarmpose: warning: {} ground-truth poses for {} frames: not evaluated",
                g.len(),
                r.poses.len()
            );
            None
        }
        None => None,
    };
    let mut written =
        write_text_outputs(r, &args.out, gt, evaluation.as_ref()).map_err(odometry_error)?;
    written
        .extend(write_plots(r, &args.out, title, gt, evaluation.as_ref()).map_err(odometry_error)?);
    let n = r.frames.len();
    let mean = |f: &dyn Fn(&swarmpose_odometry::StageTimes) -> f64| {
        r.frames.iter().map(|x| f(&x.times)).sum::<f64>() / n as f64
    };
    let total = mean(&|t| t.total_ms());
    println!(
        "{title}: {n} frames, method {}, detector {}, disparity correction {}, {} \
         constant-velocity frame(s)",
        r.method,
        r.detector,
        r.disparity_correction,
        r.n_fallbacks()
    );
    for f in r
        .frames
        .iter()
        .filter(|f| f.status.text() != "ok" && f.frame > 0)
    {
        println!("  frame {}: {}", f.frame, f.status.text());
    }
    println!(
        "time per frame: {total:.1} ms ({:.1} frames/s): load {:.1}, features {:.1}, stereo {:.1}, \
         match {:.1}, estimate {:.1}, refine {:.1} ms",
        1000.0 / total.max(1e-9),
        mean(&|t| t.load_ms),
        mean(&|t| t.features_ms),
        mean(&|t| t.stereo_ms),
        mean(&|t| t.match_ms),
        mean(&|t| t.estimate_ms),
        mean(&|t| t.refine_ms),
    );
    if let Some(e) = &evaluation {
        let drift = e
            .final_drift_percent
            .map_or_else(|| "n/a".to_owned(), |p| format!("{p:.3} %"));
        println!(
            "vs ground truth: path {:.2} m, final drift {:.3} m ({drift}), RMS eq. (20) {:.5}, \
             ATE {:.3} m raw / {:.3} m aligned, RPE {:.4} m / {:.4} deg",
            e.path_length_m,
            e.final_drift_m,
            e.eq20_rms,
            e.ate_raw.rmse,
            e.ate_aligned.rmse,
            e.rpe_translation.rmse,
            e.rpe_rotation_deg.rmse
        );
    }
    println!("written: {}", args.out.display());
    let _ = written;
    Ok(())
}
