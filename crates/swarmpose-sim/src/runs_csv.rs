//! `runs.csv`: one row per run and estimator, with a header.

use std::fmt::Write as _;

use crate::metrics::RunRecord;

/// The header of `runs.csv`.
pub const RUNS_HEADER: &str = "noise_sigma_m,outlier_fraction,run,seed,estimator,threshold_m,\
n,n_outliers,position_error_m,rotation_error_deg,rotation_error_frobenius,success,\
n_inliers_estimated,inlier_precision,inlier_recall,elapsed_ms,iterations,error";

/// A number, or an empty field for NaN (no pose).
fn num(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        format!("{v}")
    }
}

/// A text field, quoted when it holds a comma, a quote or a line break.
fn text(s: &str) -> String {
    if s.contains([',', '"', '\n', '\r']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_owned()
    }
}

/// The whole `runs.csv` text.
#[must_use]
pub fn runs_csv(rows: &[RunRecord]) -> String {
    let mut out = String::with_capacity(rows.len() * 160);
    out.push_str(RUNS_HEADER);
    out.push('\n');
    for r in rows {
        // Writing into a String cannot fail.
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{:.4},{},{}",
            r.noise_sigma,
            r.outlier_fraction,
            r.run,
            r.seed,
            text(&r.estimator),
            r.threshold_m,
            r.n,
            r.n_outliers,
            num(r.position_error_m),
            num(r.rotation_error_deg),
            num(r.rotation_error_frobenius),
            r.success,
            r.n_inliers_estimated,
            num(r.inlier_precision),
            num(r.inlier_recall),
            r.elapsed_ms,
            r.iterations,
            text(r.error.as_deref().unwrap_or("")),
        );
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn errors_with_commas_are_quoted_and_nan_is_empty() {
        let rec = RunRecord {
            noise_sigma: 0.02,
            outlier_fraction: 0.1,
            run: 3,
            seed: 1003,
            estimator: "pso-paper".into(),
            threshold_m: 0.06736,
            n: 150,
            n_outliers: 15,
            position_error_m: f64::NAN,
            rotation_error_deg: f64::NAN,
            rotation_error_frobenius: f64::NAN,
            success: false,
            n_inliers_estimated: 0,
            inlier_precision: f64::NAN,
            inlier_recall: f64::NAN,
            elapsed_ms: 1.5,
            iterations: 0,
            error: Some("insufficient support: 1 features, at least 4".into()),
        };
        let csv = runs_csv(&[rec]);
        let lines: Vec<&str> = csv.lines().collect();
        assert_eq!(lines[0], RUNS_HEADER);
        assert!(lines[1].ends_with(",\"insufficient support: 1 features, at least 4\""));
        assert!(lines[1].contains(",15,,,,false,0,,,1.5000,0,"));
        assert_eq!(
            lines[0].split(',').count(),
            lines[1].split(',').count() - 1,
            "one comma inside the quoted error"
        );
    }
}
