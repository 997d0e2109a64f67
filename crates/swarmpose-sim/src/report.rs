//! `summary.md`: tables like the paper's and the peers', per noise level, estimator x
//! outlier fraction; and the short table printed at the end of a run.

use std::fmt::Write as _;

use crate::estimators::oracle_threshold;
use crate::experiment::Experiment;
use crate::metrics::{SUCCESS_POSITION_M, SUCCESS_ROTATION_DEG};
use crate::stats::{Cell, Summary};

/// A value with about 3 significant digits; `no pose` for an infinite median.
#[must_use]
pub fn fmt_value(v: f64) -> String {
    if v.is_nan() {
        "-".to_owned()
    } else if v.is_infinite() {
        "no pose".to_owned()
    } else if v == 0.0 {
        "0".to_owned()
    } else if v.abs() < 1e-3 {
        format!("{v:.1e}")
    } else if v.abs() < 10.0 {
        format!("{v:.3}")
    } else {
        format!("{v:.1}")
    }
}

/// One markdown table: a row per estimator, a column per outlier fraction.
fn table(out: &mut String, title: &str, s: &Summary, noise: usize, cell: &dyn Fn(&Cell) -> String) {
    let _ = writeln!(out, "{title}\n");
    out.push_str("| estimator |");
    for f in &s.fractions {
        let _ = write!(out, " {f} |");
    }
    out.push_str("\n|---|");
    out.push_str(&"---|".repeat(s.fractions.len()));
    out.push('\n');
    for (e, name) in s.estimators.iter().enumerate() {
        let _ = write!(out, "| {name} |");
        for c in &s.cells[e][noise] {
            let _ = write!(out, " {} |", cell(c));
        }
        out.push('\n');
    }
    out.push('\n');
}

fn pct(v: f64) -> String {
    if v.is_nan() {
        "-".into()
    } else {
        format!("{v:.0}")
    }
}

/// The text of `summary.md`.
#[must_use]
pub fn summary_markdown(exp: &Experiment, s: &Summary, wall_s: f64, threads: usize) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "# swarmpose simulate: the paper's section-6 simulation\n\n\
         - Scenes: {} runs per cell, run seeds {}..{} (the same scene and camera motion at \
         every noise level and outlier fraction), outlier mode `{}`, median {} \
         correspondences per scenario (points of a 12 x 12 x 23 m box visible in both \
         1241 x 376 images).\n\
         - Outlier fractions (columns): {:?}; noise σ per axis on `dst`: {:?} m.\n\
         - Thresholds: every estimator gets the peers' oracle inlier threshold \
         `max(3.368 σ, 0.01)` m: {}.\n\
         - Success: rotation error < {SUCCESS_ROTATION_DEG}° and position error < \
         {SUCCESS_POSITION_M} m. A run where the estimator returned no pose (an error, \
         e.g. too little support) is a failure and counts as an infinite error in \
         medians (`no pose` = at least half the runs gave none).\n\
         - Position error = `|t_est - t_true|` (m); rotation error = angle of \
         `R_true R_est^T` (deg) and the paper's eq. (20) `||I - R_true R_est^T||_F`; \
         time = the estimator's own wall time per call.\n\
         - {} estimations in {wall_s:.1} s of wall time on {threads} thread(s).\n",
        exp.runs,
        exp.run_seed(0),
        exp.run_seed(exp.runs - 1),
        exp.mode,
        s.median_n,
        exp.fractions,
        exp.noise_levels,
        exp.noise_levels
            .iter()
            .map(|&n| format!("σ {n} → δ {:.4} m", oracle_threshold(n)))
            .collect::<Vec<_>>()
            .join(", "),
        exp.scenarios() * s.estimators.len(),
    );
    for (i, noise) in s.noise_levels.iter().enumerate() {
        let _ = writeln!(
            out,
            "## Noise σ = {noise} m (threshold δ = {:.4} m)\n",
            oracle_threshold(*noise)
        );
        table(
            &mut out,
            "Success rate (%)",
            s,
            i,
            &|c| pct(c.success_pct()),
        );
        table(&mut out, "Median position error (m)", s, i, &|c| {
            fmt_value(c.position_m.median)
        });
        table(&mut out, "Median rotation error (deg)", s, i, &|c| {
            fmt_value(c.rotation_deg.median)
        });
        table(&mut out, "Median rotation error, eq. (20)", s, i, &|c| {
            fmt_value(c.rotation_frobenius.median)
        });
        table(&mut out, "Median time (ms)", s, i, &|c| {
            fmt_value(c.time_ms.median)
        });
        table(
            &mut out,
            "Inlier precision / recall against the truth (%, mean over the runs with a pose; \"(k none)\": k runs gave no pose)",
            s,
            i,
            &|c| {
                format!(
                    "{} / {}{}",
                    pct(100.0 * c.precision),
                    pct(100.0 * c.recall),
                    if c.no_pose > 0 {
                        format!(" ({} none)", c.no_pose)
                    } else {
                        String::new()
                    }
                )
            },
        );
    }
    out
}

/// The short table printed at the end: per noise level, a row per outlier fraction and
/// a column per estimator with its success rate and median position error.
#[must_use]
pub fn console_summary(s: &Summary) -> String {
    let mut out = String::new();
    for (i, noise) in s.noise_levels.iter().enumerate() {
        let _ = writeln!(
            out,
            "noise {noise} m (threshold {:.4} m): success % / median position error (m)",
            oracle_threshold(*noise)
        );
        let _ = write!(out, "  {:>8}", "outliers");
        for name in &s.estimators {
            let _ = write!(out, " {name:>17}");
        }
        out.push('\n');
        for (j, f) in s.fractions.iter().enumerate() {
            let _ = write!(out, "  {f:>8}");
            for e in 0..s.estimators.len() {
                let c = &s.cells[e][i][j];
                let v = format!(
                    "{:>3} / {}",
                    pct(c.success_pct()),
                    fmt_value(c.position_m.median)
                );
                let _ = write!(out, " {v:>17}");
            }
            out.push('\n');
        }
    }
    out
}
