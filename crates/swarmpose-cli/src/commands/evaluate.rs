//! `swarmpose evaluate ESTIMATE GROUND_TRUTH [--format kitti|tum] [--json]`: how far an
//! estimated trajectory is from the ground truth: the paper's eq. (20) per frame and its
//! RMS (Table I), ATE raw and after SE(3) Umeyama alignment, RPE per frame, final drift,
//! and the KITTI devkit segment errors when the path is long enough; with
//! `--kitti-segments`, those in detail (per length, `--segment-scale`, `--segment-plot`).

use std::fmt::Write as _;
use std::path::PathBuf;

use clap::{Args, ValueEnum};
use swarmpose_eval::associate::{DEFAULT_MAX_DIFF_S, by_index, by_timestamp};
use swarmpose_eval::{EvalError, Evaluation, Format, Stats, Trajectory, evaluate_with};

use super::segments;
use crate::error::{CliError, EXIT_NOT_USABLE};
use crate::streams::{out, out_text};

/// File format of both trajectories.
#[derive(Debug, Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum FormatArg {
    /// One row-major 3x4 `[R|t]` per line; poses associated by line.
    Kitti,
    /// `timestamp tx ty tz qx qy qz qw` per line; poses associated by timestamp.
    Tum,
}

impl From<FormatArg> for Format {
    fn from(f: FormatArg) -> Self {
        match f {
            FormatArg::Kitti => Format::Kitti,
            FormatArg::Tum => Format::Tum,
        }
    }
}

/// Arguments of `swarmpose evaluate`.
#[derive(Debug, Args)]
#[command(after_help = "\
Metrics (definitions of evo: evo_ape, evo_rpe --delta 1 --delta_unit f): eq. (20) \
||I - R_gt R_est^T||_F between the relative rotations of each consecutive pair of \
frames and its RMS (our Table I); ATE (position error per frame, metres) raw and after \
SE(3) Umeyama alignment of the estimate onto the ground truth (no scale); RPE per \
consecutive pair (translation metres, rotation degrees); final drift (last position \
error after re-basing the estimate on the first true pose) in metres and percent of \
the ground-truth path length; KITTI devkit segment errors (100-800 m) when the path is \
at least 100 m long.

--kitti-segments prints only the KITTI devkit's figures (evaluate_odometry.cpp): for \
segments of 100, 200, ..., 800 m of ground-truth path starting every 10 frames, the \
translation error of the segment's relative pose in percent of its length and its \
rotation error in degrees per 100 m, per length and over all segments (with --json: that \
object, every segment included). A clip shorter than 100 m has none: --segment-scale 0.1 \
uses 10-80 m segments instead, and the output says they are not the KITTI figures.

Exit status: 0 on success; 2 for bad options or input (unreadable or malformed file, \
the ground truth has fewer poses than the estimate, too few poses); 3 when a metric is \
not a finite number (for example from translations near 1e308: the result is printed \
but not usable); 1 when standard output cannot be written (a closed pipe ends quietly).")]
pub struct EvaluateArgs {
    /// Estimated trajectory.
    #[arg(value_name = "ESTIMATE")]
    pub estimate: PathBuf,

    /// Ground-truth trajectory.
    #[arg(value_name = "GROUND_TRUTH")]
    pub ground_truth: PathBuf,

    /// Format of both files [default: tum for *.tum.txt or groundtruth.txt, else kitti].
    #[arg(long, value_enum)]
    pub format: Option<FormatArg>,

    /// TUM association: largest time difference of paired poses, seconds.
    #[arg(long, value_name = "S", default_value_t = DEFAULT_MAX_DIFF_S)]
    pub max_diff: f64,

    /// Print one JSON object (every metric and per-frame value) instead of the table.
    #[arg(long)]
    pub json: bool,

    /// Print only the KITTI devkit's segment errors, per segment length and averaged.
    #[arg(long)]
    pub kitti_segments: bool,

    /// Multiply the KITTI segment lengths (100-800 m) by F in (0, 1], for short clips.
    #[arg(
        long,
        value_name = "F",
        default_value_t = 1.0,
        requires = "kitti_segments"
    )]
    pub segment_scale: f64,

    /// Write the devkit's plots of the segment errors against the length to FILE.svg.
    #[arg(long, value_name = "FILE.svg", requires = "kitti_segments")]
    pub segment_plot: Option<PathBuf>,
}

fn usage(e: EvalError) -> CliError {
    CliError::usage(e.to_string())
}

/// Reads, associates and evaluates the two trajectories.
///
/// # Errors
/// Bad input, as [`CliError::usage`].
pub fn evaluate_files(args: &EvaluateArgs) -> Result<Evaluation, CliError> {
    if !(args.max_diff.is_finite() && args.max_diff >= 0.0) {
        return Err(CliError::usage(
            "--max-diff must be a finite number of seconds >= 0",
        ));
    }
    let format = args
        .format
        .map_or_else(|| Format::guess(&args.estimate), Format::from);
    let est = Trajectory::read(&args.estimate, format).map_err(usage)?;
    let gt = Trajectory::read(&args.ground_truth, format).map_err(usage)?;
    let pairs = match format {
        Format::Kitti => {
            if gt.len() < est.len() {
                return Err(CliError::usage(format!(
                    "{}: {} ground-truth poses for {} estimated frames ({}): the ground truth \
                     needs one pose per frame",
                    gt.name,
                    gt.len(),
                    est.len(),
                    est.name
                )));
            }
            by_index(&est, &gt).map_err(usage)?
        }
        Format::Tum => by_timestamp(&est, &gt, args.max_diff).map_err(usage)?,
    };
    evaluate_with(&pairs, args.segment_scale).map_err(usage)
}

fn stats_row(out: &mut String, name: &str, unit: &str, s: &Stats) {
    let _ = writeln!(
        out,
        "{name:<28} {unit:<4} {:>10.6} {:>10.6} {:>10.6} {:>10.6} {:>10.6}",
        s.rmse, s.mean, s.median, s.std, s.max
    );
}

/// The table printed on standard output.
#[must_use]
pub fn table(e: &Evaluation, args: &EvaluateArgs) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "estimate {} vs ground truth {}: {} poses paired, path {:.3} m",
        args.estimate.display(),
        args.ground_truth.display(),
        e.n_pairs,
        e.path_length_m
    );
    let _ = writeln!(
        s,
        "{:<28} {:<4} {:>10} {:>10} {:>10} {:>10} {:>10}",
        "metric", "unit", "rmse", "mean", "median", "std", "max"
    );
    stats_row(
        &mut s,
        "eq. (20) relative, per frame",
        "-",
        &Stats::of(&e.eq20_per_frame),
    );
    stats_row(&mut s, "ATE raw", "m", &e.ate_raw);
    stats_row(&mut s, "ATE SE(3)-aligned", "m", &e.ate_aligned);
    stats_row(&mut s, "RPE translation (1 frame)", "m", &e.rpe_translation);
    stats_row(&mut s, "RPE rotation (1 frame)", "deg", &e.rpe_rotation_deg);
    let _ = writeln!(s, "RMS eq. (20) (Table I): {:.6}", e.eq20_rms);
    let _ = writeln!(
        s,
        "RMS eq. (20) of absolute orientations: {:.6}",
        e.eq20_absolute_rms
    );
    match e.final_drift_percent {
        Some(p) => {
            let _ = writeln!(
                s,
                "final drift: {:.4} m = {p:.3} % of {:.3} m",
                e.final_drift_m, e.path_length_m
            );
        }
        None => {
            let _ = writeln!(
                s,
                "final drift: {:.4} m (path too short for a percentage)",
                e.final_drift_m
            );
        }
    }
    match (e.kitti.translation_percent, e.kitti.rotation_deg_per_100m) {
        (Some(t), Some(r)) => {
            let _ = writeln!(
                s,
                "KITTI segments: translation {t:.3} %, rotation {r:.4} deg/100 m ({})",
                e.kitti.note
            );
        }
        _ => {
            let _ = writeln!(s, "KITTI segments: {}", e.kitti.note);
        }
    }
    s
}

/// Runs `evaluate`.
///
/// # Errors
/// Bad input (exit 2).
pub fn run(args: &EvaluateArgs) -> Result<(), CliError> {
    let e = evaluate_files(args)?;
    if args.kitti_segments {
        return run_segments(&e, args);
    }
    if args.json {
        let text = serde_json::to_string(&e)
            .map_err(|err| CliError::failure(format!("cannot encode JSON: {err}")))?;
        out(&text)?;
    } else {
        out_text(&table(&e, args))?;
    }
    if let Some(name) = first_non_finite(&e) {
        return Err(CliError {
            code: EXIT_NOT_USABLE,
            message: format!(
                "not usable: {name} is not a finite number (the poses are too large for \
                 double precision?); the metrics above cannot be trusted"
            ),
        });
    }
    Ok(())
}

/// `--kitti-segments`: the segment table (or its JSON) and the plot.
fn run_segments(e: &Evaluation, args: &EvaluateArgs) -> Result<(), CliError> {
    let k = &e.kitti;
    if k.segments.is_empty() {
        // A segment needs more path than its length: the largest scale in hundredths.
        let largest = ((e.path_length_m - 1e-6).floor() / 100.0).min(1.0);
        let hint = if largest >= 0.01 {
            format!("; --segment-scale {largest:.2} or less gives segments")
        } else {
            String::new()
        };
        return Err(CliError::usage(format!("KITTI segments {}{hint}", k.note)));
    }
    // The plot first: a plot that cannot be written fails before anything is printed.
    if let Some(path) = &args.segment_plot {
        segments::write_segment_plot(k, &args.estimate, path)?;
    }
    if args.json {
        let text = serde_json::to_string(k)
            .map_err(|err| CliError::failure(format!("cannot encode JSON: {err}")))?;
        out(&text)?;
    } else {
        out_text(&segments::segment_table(k, &args.estimate))?;
    }
    if let Some(name) = first_non_finite(e) {
        return Err(CliError {
            code: EXIT_NOT_USABLE,
            message: format!("not usable: {name} is not a finite number"),
        });
    }
    Ok(())
}

/// The name of the first metric of `e` that is not a finite number, if any.
#[must_use]
pub fn first_non_finite(e: &Evaluation) -> Option<&'static str> {
    let stats = |s: &Stats| [s.rmse, s.mean, s.median, s.std, s.min, s.max];
    let finite = |v: &[f64]| v.iter().all(|x| x.is_finite());
    let checks: [(&'static str, bool); 10] = [
        ("the path length", e.path_length_m.is_finite()),
        (
            "eq. (20)",
            e.eq20_rms.is_finite() && finite(&e.eq20_per_frame),
        ),
        (
            "eq. (20) of absolute orientations",
            e.eq20_absolute_rms.is_finite(),
        ),
        (
            "ATE raw",
            finite(&stats(&e.ate_raw)) && finite(&e.ate_raw_per_frame),
        ),
        (
            "ATE aligned",
            finite(&stats(&e.ate_aligned)) && finite(&e.ate_aligned_per_frame),
        ),
        (
            "RPE translation",
            finite(&stats(&e.rpe_translation)) && finite(&e.rpe_translation_per_frame),
        ),
        (
            "RPE rotation",
            finite(&stats(&e.rpe_rotation_deg)) && finite(&e.rpe_rotation_deg_per_frame),
        ),
        ("the final drift", e.final_drift_m.is_finite()),
        (
            "the final drift in percent",
            e.final_drift_percent.is_none_or(f64::is_finite),
        ),
        (
            "the KITTI segment errors",
            e.kitti.translation_percent.is_none_or(f64::is_finite)
                && e.kitti.rotation_deg_per_100m.is_none_or(f64::is_finite),
        ),
    ];
    checks.iter().find(|c| !c.1).map(|c| c.0)
}
