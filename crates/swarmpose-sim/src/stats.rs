//! Aggregates of the runs: quartiles and rates per (estimator, noise, fraction).

use crate::experiment::Experiment;
use crate::metrics::RunRecord;

/// First quartile, median and third quartile (linear interpolation between order
/// statistics). A run without a pose counts as `+∞`, so a median is infinite when at
/// least half the runs gave no pose.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quartiles {
    /// 25th percentile.
    pub q1: f64,
    /// Median.
    pub median: f64,
    /// 75th percentile.
    pub q3: f64,
}

/// The `p`-quantile (`p ∈ [0, 1]`) of values sorted in ascending order, `NaN` for none:
/// the project's one quantile definition, used by the simulation's quartiles, `swarmpose
/// bench`'s tables and the pipeline benchmark's latencies.
///
/// Linear interpolation between order statistics (type 7 of Hyndman and Fan, 1996; the
/// default of R and NumPy): with `n` values, the position `h = p (n − 1)` (0-based), and
/// the quantile `x[⌊h⌋] + (h − ⌊h⌋) (x[⌈h⌉] − x[⌊h⌋])`; the median of an even count is
/// the mean of the middle two. An interpolation towards `+∞` is `+∞` (a run without a
/// pose counts as `+∞`).
#[must_use]
pub fn quantile(sorted: &[f64], p: f64) -> f64 {
    if sorted.is_empty() {
        return f64::NAN;
    }
    let pos = p * (sorted.len() - 1) as f64;
    let lo = pos.floor() as usize;
    let hi = pos.ceil() as usize;
    let frac = pos - lo as f64;
    if hi == lo || frac == 0.0 {
        sorted[lo]
    } else if sorted[hi].is_infinite() {
        f64::INFINITY
    } else {
        sorted[lo] + (sorted[hi] - sorted[lo]) * frac
    }
}

impl Quartiles {
    /// Quartiles of `values`, NaN counted as `+∞`.
    #[must_use]
    pub fn of(values: impl IntoIterator<Item = f64>) -> Self {
        let mut v: Vec<f64> = values
            .into_iter()
            .map(|x| if x.is_nan() { f64::INFINITY } else { x })
            .collect();
        v.sort_by(f64::total_cmp);
        Self {
            q1: quantile(&v, 0.25),
            median: quantile(&v, 0.5),
            q3: quantile(&v, 0.75),
        }
    }
}

/// Aggregates of one estimator at one (noise, fraction).
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// Runs.
    pub runs: usize,
    /// Runs where the estimator returned no pose.
    pub no_pose: usize,
    /// Successful runs.
    pub successes: usize,
    /// Position error, metres.
    pub position_m: Quartiles,
    /// Rotation error, degrees.
    pub rotation_deg: Quartiles,
    /// Eq. (20) rotation error.
    pub rotation_frobenius: Quartiles,
    /// Time, milliseconds.
    pub time_ms: Quartiles,
    /// Mean inlier precision over runs with a pose (NaN for none).
    pub precision: f64,
    /// Mean inlier recall over runs with a pose (NaN for none).
    pub recall: f64,
}

impl Cell {
    /// Success rate in percent.
    #[must_use]
    pub fn success_pct(&self) -> f64 {
        if self.runs == 0 {
            f64::NAN
        } else {
            100.0 * self.successes as f64 / self.runs as f64
        }
    }

    fn of(rows: &[&RunRecord]) -> Self {
        let mean = |f: fn(&RunRecord) -> f64| {
            let v: Vec<f64> = rows.iter().map(|r| f(r)).filter(|x| !x.is_nan()).collect();
            if v.is_empty() {
                f64::NAN
            } else {
                v.iter().sum::<f64>() / v.len() as f64
            }
        };
        Self {
            runs: rows.len(),
            no_pose: rows.iter().filter(|r| r.error.is_some()).count(),
            successes: rows.iter().filter(|r| r.success).count(),
            position_m: Quartiles::of(rows.iter().map(|r| r.position_error_m)),
            rotation_deg: Quartiles::of(rows.iter().map(|r| r.rotation_error_deg)),
            rotation_frobenius: Quartiles::of(rows.iter().map(|r| r.rotation_error_frobenius)),
            time_ms: Quartiles::of(rows.iter().map(|r| r.elapsed_ms)),
            precision: mean(|r| r.inlier_precision),
            recall: mean(|r| r.inlier_recall),
        }
    }
}

/// Every cell of an experiment, indexed `[estimator][noise][fraction]`.
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// Estimator names, in run order.
    pub estimators: Vec<String>,
    /// Noise levels, metres.
    pub noise_levels: Vec<f64>,
    /// Outlier fractions.
    pub fractions: Vec<f64>,
    /// `cells[e][i][j]`: estimator `e`, noise `i`, fraction `j`.
    pub cells: Vec<Vec<Vec<Cell>>>,
    /// Median number of correspondences per scenario.
    pub median_n: usize,
}

impl Summary {
    /// Aggregates `rows` of `experiment` (estimators in order of first appearance).
    #[must_use]
    pub fn new(experiment: &Experiment, rows: &[RunRecord]) -> Self {
        let mut estimators: Vec<String> = Vec::new();
        for r in rows {
            if !estimators.contains(&r.estimator) {
                estimators.push(r.estimator.clone());
            }
        }
        let cells = estimators
            .iter()
            .map(|name| {
                experiment
                    .noise_levels
                    .iter()
                    .map(|&noise| {
                        experiment
                            .fractions
                            .iter()
                            .map(|&f| {
                                let sel: Vec<&RunRecord> = rows
                                    .iter()
                                    .filter(|r| {
                                        &r.estimator == name
                                            && r.noise_sigma == noise
                                            && r.outlier_fraction == f
                                    })
                                    .collect();
                                Cell::of(&sel)
                            })
                            .collect()
                    })
                    .collect()
            })
            .collect();
        let mut ns: Vec<usize> = rows.iter().map(|r| r.n).collect();
        ns.sort_unstable();
        Self {
            estimators,
            noise_levels: experiment.noise_levels.clone(),
            fractions: experiment.fractions.clone(),
            cells,
            median_n: ns.get(ns.len() / 2).copied().unwrap_or(0),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quartiles_interpolate_and_count_failures_as_infinite() {
        let q = Quartiles::of([1.0, 2.0, 3.0, 4.0, 5.0]);
        assert_eq!((q.q1, q.median, q.q3), (2.0, 3.0, 4.0));
        let q = Quartiles::of([1.0, 2.0, 3.0, 4.0]);
        assert!((q.median - 2.5).abs() < 1e-12);
        let q = Quartiles::of([1.0, 2.0, f64::NAN, f64::NAN, f64::NAN]);
        assert!(q.median.is_infinite() && (q.q1 - 2.0).abs() < 1e-12);
        assert!(Quartiles::of([]).median.is_nan());
    }
}
