//! `runs.csv`: one row per run and estimator, with a header.

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

/// The fields of one row, in the order of [`RUNS_HEADER`].
fn fields(r: &RunRecord) -> [String; 18] {
    [
        r.noise_sigma.to_string(),
        r.outlier_fraction.to_string(),
        r.run.to_string(),
        r.seed.to_string(),
        r.estimator.clone(),
        r.threshold_m.to_string(),
        r.n.to_string(),
        r.n_outliers.to_string(),
        num(r.position_error_m),
        num(r.rotation_error_deg),
        num(r.rotation_error_frobenius),
        r.success.to_string(),
        r.n_inliers_estimated.to_string(),
        num(r.inlier_precision),
        num(r.inlier_recall),
        format!("{:.4}", r.elapsed_ms),
        r.iterations.to_string(),
        r.error.clone().unwrap_or_default(),
    ]
}

/// The whole `runs.csv` text (written by the `csv` crate: a field is quoted when it holds
/// a comma, a quote or a line break).
///
/// # Errors
/// The `csv` crate's (none is expected: the text is built in memory).
pub fn runs_csv(rows: &[RunRecord]) -> Result<String, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::with_capacity(rows.len() * 160));
    w.write_record(RUNS_HEADER.split(','))?;
    for r in rows {
        w.write_record(fields(r))?;
    }
    let bytes = w
        .into_inner()
        .map_err(|e| csv::Error::from(e.into_error()))?;
    String::from_utf8(bytes).map_err(|e| csv::Error::from(std::io::Error::other(e)))
}

/// Reads back the rows of a `runs.csv` ([`runs_csv`]): the same values (numbers are
/// written in their shortest exact form; `elapsed_ms` at its four decimals).
///
/// # Errors
/// The line and field that cannot be read.
pub fn parse_runs_csv(text: &str) -> Result<Vec<RunRecord>, String> {
    let mut reader = csv::ReaderBuilder::new()
        .flexible(true)
        .from_reader(text.as_bytes());
    let header = reader
        .headers()
        .map_err(|e| format!("not a runs.csv: {e}"))?;
    if header.iter().ne(RUNS_HEADER.split(',')) {
        return Err("not a runs.csv: its first line is not the header".into());
    }
    reader
        .records()
        .map(|record| {
            let record = record.map_err(|e| e.to_string())?;
            let line = record.position().map_or(0, csv::Position::line);
            let f: Vec<String> = record.iter().map(str::to_owned).collect();
            parse_row(&f).map_err(|e| format!("line {line}: {e}"))
        })
        .collect()
}

fn parse_row(f: &[String]) -> Result<RunRecord, String> {
    if f.len() != 18 {
        return Err(format!("{} fields, 18 expected", f.len()));
    }
    fn p<T: std::str::FromStr>(f: &[String], k: usize) -> Result<T, String> {
        f[k].parse()
            .map_err(|_| format!("field {} '{}' is not a number", k + 1, f[k]))
    }
    let nan = |k: usize| -> Result<f64, String> {
        if f[k].is_empty() {
            Ok(f64::NAN)
        } else {
            p(f, k)
        }
    };
    Ok(RunRecord {
        noise_sigma: p(f, 0)?,
        outlier_fraction: p(f, 1)?,
        run: p(f, 2)?,
        seed: p(f, 3)?,
        estimator: f[4].clone(),
        threshold_m: p(f, 5)?,
        n: p(f, 6)?,
        n_outliers: p(f, 7)?,
        position_error_m: nan(8)?,
        rotation_error_deg: nan(9)?,
        rotation_error_frobenius: nan(10)?,
        success: p(f, 11)?,
        n_inliers_estimated: p(f, 12)?,
        inlier_precision: nan(13)?,
        inlier_recall: nan(14)?,
        elapsed_ms: p(f, 15)?,
        iterations: p(f, 16)?,
        error: Some(f[17].clone()).filter(|e| !e.is_empty()),
    })
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
            elapsed_ms: 1.5,
            error: Some("insufficient support: 1 features, at least 4".into()),
            ..RunRecord::without_pose()
        };
        let csv = runs_csv(std::slice::from_ref(&rec)).expect("written");
        let back = parse_runs_csv(&csv).expect("parse");
        assert_eq!(
            runs_csv(&back).expect("written"),
            csv,
            "read back, written again: the same bytes"
        );
        assert_eq!(back[0].error, rec.error);
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
