//! `swarmpose bench SUITE_DIR`: our estimators on a folder of scenario files (CSV +
//! truth JSON, the format of `gen_scenarios.py`), tabulated per cell like the peers'
//! `RESULTS.md`, so the comparison can be repeated by anyone.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

use clap::Args;
use nalgebra::Isometry3;
use swarmpose_core::geometry::rotation_angle_between;
use swarmpose_core::{Correspondences, Estimator, Method};
use swarmpose_data::{correspondence_csv, truth};
use swarmpose_sim::StereoSpec;

use crate::error::CliError;

/// Largest rotation error of a success, degrees (as the peers).
const SUCCESS_ROTATION_DEG: f64 = 2.0;
/// Largest translation error of a success, metres (as the peers).
const SUCCESS_TRANSLATION_M: f64 = 0.2;
/// The bench's own entries beside the core's registry ([`Method`]): `pso-auto` (`pso`
/// with its automatic threshold), `oracle-inliers` (`svd` on the true inliers) and
/// `oracle-weighted` (`wls` on the true inliers).
const BENCH_ONLY: [&str; 3] = ["pso-auto", "oracle-inliers", "oracle-weighted"];

/// Every name the bench knows: the registry's, then its own.
fn all_methods() -> Vec<&'static str> {
    Method::ALL
        .iter()
        .map(|m| m.name())
        .chain(BENCH_ONLY)
        .collect()
}

/// Arguments of `swarmpose bench`.
#[derive(Debug, Args)]
#[command(after_help = "\
Each NAME.csv in SUITE_DIR needs its truth NAME.json beside it (gen_scenarios.py writes \
both). Estimators run one at a time on one thread; the time is that of the estimation call \
only. Thresholds: the peers' oracle max(3.368 sigma, 0.01) m from the truth's noise_sigma, \
except pso-auto, which estimates its own; oracle-inliers is SVD on the truth's inlier \
labels, the ceiling of any method that ends with a least-squares fit; oracle-weighted is \
wls (weighted by the CSV's noise model, Mahalanobis with covariances) on them. Success: rotation error < 2 deg and translation \
error < 0.2 m. Prints Markdown tables per outlier mode and noise level: success rate, \
median and 90th-percentile rotation error, median translation error, median time.")]
pub struct BenchArgs {
    /// Folder of scenario CSV + truth JSON files.
    #[arg(value_name = "SUITE_DIR", required_unless_present = "stereo")]
    pub suite: Option<PathBuf>,

    /// Instead of a folder: N generated stereo-noise scenarios per outlier fraction
    /// (0.9, 0.95, 0.97; street scene, 600 correspondences with their covariances,
    /// wrong matches onto other scene points; swarmpose-sim's `StereoSpec`).
    #[arg(long, value_name = "N", conflicts_with = "suite")]
    pub stereo: Option<u64>,

    /// Estimators, comma separated, from pso, pso-paper, svd, msac, wls, pso-auto,
    /// oracle-inliers (SVD on the truth's inliers only: the least-squares ceiling) and
    /// oracle-weighted (wls on them: the weighted ceiling).
    #[arg(long, value_delimiter = ',', default_value = "pso,pso-auto,msac")]
    pub methods: Vec<String>,

    /// Only scenario files whose name contains this text (e.g. "random_n0.020").
    #[arg(long, value_name = "TEXT", default_value = "")]
    pub filter: String,

    /// Seed of every estimation (a hash of the scenario's file name is added, so a
    /// scenario gets the same seed whatever the filter).
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,

    /// Also write one row per (scenario, method) to this CSV file: scenario, method,
    /// success, rotation_deg, translation_m, time_ms, inliers (empty fields on failure).
    #[arg(long, value_name = "FILE")]
    pub runs_csv: Option<PathBuf>,
}

/// One estimation judged against the truth.
struct Outcome {
    scenario: String,
    inliers: Option<usize>,
    success: bool,
    rotation_deg: f64,
    translation_m: f64,
    elapsed_ms: f64,
}

/// FNV-1a of `text`: a seed offset that does not depend on the platform or the filter.
fn stable_hash(text: &str) -> u64 {
    text.bytes().fold(0xcbf2_9ce4_8422_2325, |h, b| {
        (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3)
    })
}

/// One CSV row per (scenario, method), in table order (written by the `csv` crate: a
/// scenario name with a comma or a quote is quoted).
///
/// # Errors
/// The `csv` crate's (none is expected: the text is built in memory).
fn runs_csv(results: &Results) -> Result<Vec<u8>, csv::Error> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record([
        "scenario",
        "method",
        "success",
        "rotation_deg",
        "translation_m",
        "time_ms",
        "inliers",
    ])?;
    let opt = |v: f64| {
        if v.is_finite() {
            format!("{v:.6}")
        } else {
            String::new()
        }
    };
    for fractions in results.values() {
        for methods in fractions.values() {
            for (method, outcomes) in methods {
                for o in outcomes {
                    w.write_record([
                        o.scenario.clone(),
                        method.clone(),
                        u8::from(o.success).to_string(),
                        opt(o.rotation_deg),
                        opt(o.translation_m),
                        format!("{:.4}", o.elapsed_ms),
                        o.inliers.map_or_else(String::new, |n| n.to_string()),
                    ])?;
                }
            }
        }
    }
    w.into_inner().map_err(|e| csv::Error::from(e.into_error()))
}

/// The peers' oracle threshold for noise σ (metres).
fn oracle_threshold(sigma: f64) -> f64 {
    (3.368 * sigma).max(0.01)
}

fn estimator(name: &str, sigma: f64) -> Option<Box<dyn Estimator>> {
    let thr = oracle_threshold(sigma);
    let method = match name {
        "pso-auto" => return Some(Method::Pso.build(None)),
        "oracle-inliers" => Method::Svd,
        "oracle-weighted" => Method::Wls,
        other => Method::from_name(other)?,
    };
    Some(method.build(method.uses_threshold().then_some(thr)))
}

fn scenario_files(dir: &Path, filter: &str) -> Result<Vec<PathBuf>, CliError> {
    let entries = std::fs::read_dir(dir)
        .map_err(|e| CliError::usage(format!("{}: cannot read the folder: {e}", dir.display())))?;
    let mut files: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|x| x == "csv"))
        .filter(|p| {
            p.file_name()
                .is_some_and(|n| n.to_string_lossy().contains(filter))
        })
        .collect();
    files.sort();
    if files.is_empty() {
        return Err(CliError::usage(format!(
            "{}: no scenario .csv files{}",
            dir.display(),
            if filter.is_empty() {
                String::new()
            } else {
                format!(" matching \"{filter}\"")
            }
        )));
    }
    Ok(files)
}

/// The `q`-quantile of `v` ([`swarmpose_sim::stats::quantile`]: interpolated between
/// order statistics), NaN when empty.
fn quantile(v: &mut [f64], q: f64) -> f64 {
    v.sort_by(f64::total_cmp);
    swarmpose_sim::stats::quantile(v, q)
}

type CellKey = (String, u64); // (mode, noise in µm)

/// Runs `bench`.
///
/// # Errors
/// An unknown method, an unreadable folder or scenario file.
pub fn run(args: &BenchArgs) -> Result<(), CliError> {
    let known = all_methods();
    for m in &args.methods {
        if !known.contains(&m.as_str()) {
            return Err(CliError::usage(format!(
                "unknown method \"{m}\": use {}",
                known.join(", ")
            )));
        }
    }
    if let Some(path) = &args.runs_csv {
        crate::output_file::check_target(path)?;
    }
    // results[(mode, noise)][fraction in ppm][method] = outcomes
    let mut results: BTreeMap<CellKey, BTreeMap<u64, BTreeMap<String, Vec<Outcome>>>> =
        BTreeMap::new();
    let started = Instant::now();
    let (source, count) = match (&args.suite, args.stereo) {
        (Some(dir), _) => {
            let files = scenario_files(dir, &args.filter)?;
            for csv in &files {
                bench_case(&read_case(csv)?, args, &mut results);
            }
            (dir.display().to_string(), files.len())
        }
        (None, Some(runs)) => {
            if !(1..=MAX_STEREO_RUNS).contains(&runs) {
                return Err(CliError::usage(format!(
                    "--stereo {runs}: give 1 to {MAX_STEREO_RUNS} scenarios per outlier fraction"
                )));
            }
            let mut count = 0;
            for fraction in STEREO_FRACTIONS {
                for run in 0..runs {
                    let case = stereo_case(fraction, run)?;
                    if case.scenario.contains(&args.filter) {
                        bench_case(&case, args, &mut results);
                        count += 1;
                    }
                }
            }
            if count == 0 {
                return Err(CliError::usage(format!(
                    "--filter \"{}\" matches none of the {} generated scenarios",
                    args.filter,
                    runs * STEREO_FRACTIONS.len() as u64
                )));
            }
            ("the stereo-noise generator".to_owned(), count)
        }
        (None, None) => return Err(CliError::usage("give SUITE_DIR or --stereo N")),
    };
    if let Some(path) = &args.runs_csv {
        let text = runs_csv(&results)
            .map_err(|e| CliError::failure(format!("cannot write {}: {e}", path.display())))?;
        crate::output_file::write_bytes(path, &text)?;
    }
    crate::streams::out_text(&tables(&results, &args.methods))?;
    crate::streams::out(&format!(
        "\n{count} scenarios from {source}, {} estimators, {:.1} s wall time.",
        args.methods.len(),
        started.elapsed().as_secs_f64()
    ))
}

/// The most `--stereo` scenarios per outlier fraction (each is generated and run by
/// every method; a million would take days).
const MAX_STEREO_RUNS: u64 = 100_000;

/// Outlier fractions of `--stereo`.
const STEREO_FRACTIONS: [f64; 3] = [0.9, 0.95, 0.97];

/// One scenario with its truth.
struct Case {
    scenario: String,
    data: Correspondences,
    true_pose: Isometry3<f64>,
    /// The true inliers only.
    true_inliers: Correspondences,
    cell: CellKey,
    /// Outlier fraction, ppm.
    fraction: u64,
    noise_sigma: f64,
}

/// A scenario file and its truth beside it.
fn read_case(csv: &Path) -> Result<Case, CliError> {
    let scenario = csv
        .file_stem()
        .map_or_else(String::new, |s| s.to_string_lossy().into_owned());
    let data = correspondence_csv::read_path(csv).map_err(|e| CliError::usage(e.to_string()))?;
    let truth_path = truth::path_for_csv(csv);
    let t = truth::read(&truth_path).map_err(|e| CliError::usage(e.to_string()))?;
    let true_pose = t
        .isometry()
        .map_err(|e| CliError::usage(format!("{}: {e}", truth_path.display())))?;
    Ok(Case {
        scenario,
        true_inliers: data.select(&t.inlier_indices()),
        data,
        true_pose,
        cell: (t.mode.clone(), (t.noise_sigma * 1e6).round() as u64),
        fraction: (t.outlier_fraction * 1e6).round() as u64,
        noise_sigma: t.noise_sigma,
    })
}

/// Run `run` of the stereo-noise generator at `fraction` (seed `run`, street scene).
fn stereo_case(fraction: f64, run: u64) -> Result<Case, CliError> {
    let spec = StereoSpec::street().with_outliers(fraction);
    let s = spec
        .scenario(run)
        .map_err(|e| CliError::failure(format!("stereo scenario {run}: {e}")))?;
    Ok(Case {
        scenario: format!("stereo_o{fraction:.2}_r{run:03}"),
        true_inliers: s.data.select(&s.inlier_indices()),
        data: s.data,
        true_pose: s.truth,
        cell: ("stereo".to_owned(), 0),
        fraction: (fraction * 1e6).round() as u64,
        // No single σ: threshold-taking methods get the smallest oracle threshold.
        noise_sigma: 0.0,
    })
}

/// Every method of `args` on one scenario, into `results`.
fn bench_case(case: &Case, args: &BenchArgs, results: &mut Results) {
    let seed = args.seed.wrapping_add(stable_hash(&case.scenario));
    let (scenario, data, true_pose, true_inliers, cell, fraction) = (
        &case.scenario,
        &case.data,
        &case.true_pose,
        &case.true_inliers,
        &case.cell,
        case.fraction,
    );
    for name in &args.methods {
        let Some(est) = estimator(name, case.noise_sigma) else {
            continue;
        };
        // The reference: least squares on exactly the true inliers, the best any
        // method that ends with a least-squares fit can do.
        let input = if name.starts_with("oracle-") {
            true_inliers
        } else {
            data
        };
        let t0 = Instant::now();
        let result = est.estimate_seeded(input, seed);
        let outer_ms = t0.elapsed().as_secs_f64() * 1e3;
        let outcome = match result {
            Ok(e) => {
                let r =
                    rotation_angle_between(&e.transform.rotation, &true_pose.rotation).to_degrees();
                let tr = (e.transform.translation.vector - true_pose.translation.vector).norm();
                Outcome {
                    scenario: scenario.clone(),
                    inliers: Some(e.inliers.len()),
                    success: r < SUCCESS_ROTATION_DEG && tr < SUCCESS_TRANSLATION_M,
                    rotation_deg: r,
                    translation_m: tr,
                    elapsed_ms: e.diagnostics.elapsed.as_secs_f64() * 1e3,
                }
            }
            Err(_) => Outcome {
                scenario: scenario.clone(),
                inliers: None,
                success: false,
                rotation_deg: f64::NAN,
                translation_m: f64::NAN,
                elapsed_ms: outer_ms,
            },
        };
        results
            .entry(cell.clone())
            .or_default()
            .entry(fraction)
            .or_default()
            .entry(name.clone())
            .or_default()
            .push(outcome);
    }
}

type Results = BTreeMap<CellKey, BTreeMap<u64, BTreeMap<String, Vec<Outcome>>>>;

/// The Markdown tables: per (mode, noise), one table per statistic.
fn tables(results: &Results, methods: &[String]) -> String {
    type Stat = fn(&[Outcome]) -> String;
    let stats: [(&str, Stat); 5] = [
        ("Success rate (%)", |o| {
            format!(
                "{:.0}",
                100.0 * o.iter().filter(|x| x.success).count() as f64 / o.len() as f64
            )
        }),
        ("Median rotation error (deg)", |o| {
            fmt(quantile(&mut ok_values(o, |x| x.rotation_deg), 0.5))
        }),
        ("90th-percentile rotation error (deg)", |o| {
            fmt(quantile(&mut ok_values(o, |x| x.rotation_deg), 0.9))
        }),
        ("Median translation error (m)", |o| {
            fmt(quantile(&mut ok_values(o, |x| x.translation_m), 0.5))
        }),
        ("Median time (ms, estimation call, 1 thread)", |o| {
            fmt(quantile(
                &mut o.iter().map(|x| x.elapsed_ms).collect::<Vec<_>>(),
                0.5,
            ))
        }),
    ];
    let mut out = String::new();
    for ((mode, noise_um), by_fraction) in results {
        let fractions: Vec<String> = by_fraction
            .keys()
            .map(|f| format!("{}", *f as f64 / 1e6))
            .collect();
        for (title, stat) in &stats {
            out += &format!(
                "\n## {title} vs outlier fraction - {mode} outliers, noise {} m\n\n",
                *noise_um as f64 / 1e6
            );
            out += &format!("| method | {} |\n", fractions.join(" | "));
            out += &format!("|---|{}\n", "---|".repeat(fractions.len()));
            for m in methods {
                let cells: Vec<String> = by_fraction
                    .values()
                    .map(|by_method| match by_method.get(m) {
                        Some(o) if !o.is_empty() => {
                            let n = if o.len() == 50 {
                                String::new()
                            } else {
                                format!(" (n={})", o.len())
                            };
                            format!("{}{n}", stat(o))
                        }
                        _ => "-".into(),
                    })
                    .collect();
                out += &format!("| {m} | {} |\n", cells.join(" | "));
            }
        }
    }
    out
}

/// The values of the runs that returned a pose.
fn ok_values(o: &[Outcome], f: impl Fn(&Outcome) -> f64) -> Vec<f64> {
    o.iter().map(f).filter(|v| v.is_finite()).collect()
}

/// Three significant figures, or "-" for NaN.
fn fmt(v: f64) -> String {
    if !v.is_finite() {
        "-".into()
    } else if v >= 100.0 {
        format!("{v:.0}")
    } else if v >= 10.0 {
        format!("{v:.1}")
    } else if v >= 1.0 {
        format!("{v:.2}")
    } else {
        format!("{v:.3}")
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_and_format() {
        let mut v = vec![5.0, 1.0, 3.0, 2.0, 4.0];
        assert_eq!(quantile(&mut v, 0.5), 3.0);
        // Position 0.9 (5 − 1) = 3.6 between the sorted 4 and 5.
        assert!((quantile(&mut v, 0.9) - 4.6).abs() < 1e-12);
        assert_eq!(quantile(&mut [2.0, 1.0], 0.5), 1.5);
        assert!(quantile(&mut [], 0.5).is_nan());
        assert_eq!(fmt(0.12345), "0.123");
        assert_eq!(fmt(1234.0), "1234");
        assert_eq!(fmt(f64::NAN), "-");
    }
}
