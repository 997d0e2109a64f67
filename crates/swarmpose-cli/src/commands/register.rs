//! `swarmpose register`: estimate the rigid motion of one correspondence CSV and print
//! it as one JSON object.

use std::path::PathBuf;

use clap::Args;
use serde::Serialize;
use swarmpose_core::geometry::quaternion_wxyz;
use swarmpose_core::{Correspondences, Estimate, PoseError};

use crate::error::CliError;
use crate::input::{display_name, read_correspondences};
use crate::methods::{EstimatorOptions, Method, MethodParser, build};

/// Arguments of `swarmpose register`.
#[derive(Debug, Args)]
#[command(after_help = "\
Output: one JSON object on standard output, one line: method, input, seed, \
n_correspondences, rotation_wxyz ([w, x, y, z], w >= 0), translation ([x, y, z], metres), \
inliers (0-based row indices), inlier_ratio, noise_model (\"covariance\" when the CSV has \
the 12 covariance columns and the method is pso: Mahalanobis inlier test and fit; \
\"range\" when pso's residuals chose a noise model growing with the range along the viewing \
ray over isotropic noise, and tested and fitted with it; \"threshold\"; \"none\" for svd), threshold_m (null for svd and with covariances), \
final_cost (m^2), \
residual_rms_m, iterations, cost_evaluations, elapsed_ms, ambiguous (a second motion \
with at least half the support was found: pso only) and runner_up (its rotation_wxyz, \
translation, n_inliers; null when none), points_checksum (of the input's coordinates, \
checked by `correspondences --inliers`).

Exit status: 0 on success; 1 when the estimator found no pose with enough support; \
2 for bad options or bad input (unreadable file, malformed CSV, too few or degenerate \
points).")]
pub struct RegisterArgs {
    /// Correspondence CSV with header src_x,src_y,src_z,dst_x,dst_y,dst_z (metres,
    /// dst = R src + t), optionally followed by the 12 covariance columns
    /// src_cxx,src_cxy,src_cxz,src_cyy,src_cyz,src_czz,dst_cxx,...,dst_czz (m²), or '-'
    /// for standard input.
    #[arg(value_name = "FILE.csv|-")]
    pub input: PathBuf,

    /// Estimator.
    #[arg(long, value_parser = MethodParser, default_value = Method::Pso.name())]
    pub method: Method,

    /// Seed of the random generator; one seed gives one answer.
    #[arg(long, value_name = "N", default_value_t = 0)]
    pub seed: u64,

    #[command(flatten)]
    pub options: EstimatorOptions,
}

/// What `register` prints.
#[derive(Debug, Serialize)]
struct Report<'a> {
    method: &'a str,
    input: &'a str,
    seed: u64,
    n_correspondences: usize,
    /// Rotation of dst = R src + t, `[w, x, y, z]` with `w >= 0`.
    rotation_wxyz: [f64; 4],
    /// Translation of dst = R src + t, metres.
    translation: [f64; 3],
    inlier_ratio: f64,
    /// How the inliers were tested: "covariance" (per-point covariances from the CSV,
    /// Mahalanobis; pso only), "threshold" or "none" (svd).
    noise_model: &'static str,
    threshold_m: Option<f64>,
    final_cost: f64,
    residual_rms_m: f64,
    iterations: usize,
    cost_evaluations: u64,
    elapsed_ms: f64,
    /// True when a second motion with comparable support was found (pso only).
    ambiguous: bool,
    /// That second motion, or null.
    runner_up: Option<RunnerUpReport>,
    /// The checksum of the input's coordinates
    /// ([`swarmpose_data::register_report::points_checksum`]): `correspondences
    /// --inliers` checks it before drawing.
    points_checksum: String,
    inliers: &'a [usize],
}

/// A second motion found among the left-over correspondences.
#[derive(Debug, Serialize)]
struct RunnerUpReport {
    rotation_wxyz: [f64; 4],
    translation: [f64; 3],
    n_inliers: usize,
}

impl<'a> Report<'a> {
    fn new(
        method: &'a str,
        input: &'a str,
        seed: u64,
        data: &Correspondences,
        e: &'a Estimate,
    ) -> Self {
        let n = data.len();
        let noise_model = match (method, data.noise_covariance().is_some()) {
            ("pso", true) => "covariance",
            ("svd", _) => "none",
            _ if e.diagnostics.range_noise.is_some() => "range",
            _ => "threshold",
        };
        let t = e.transform.translation.vector;
        let d = &e.diagnostics;
        Self {
            method,
            input,
            seed,
            n_correspondences: n,
            rotation_wxyz: quaternion_wxyz(&e.transform.rotation),
            translation: [t.x, t.y, t.z],
            inlier_ratio: e.inlier_ratio(n),
            noise_model,
            threshold_m: d.threshold_m,
            final_cost: d.final_cost,
            residual_rms_m: d.residual_rms_m,
            iterations: d.iterations,
            cost_evaluations: d.cost_evaluations,
            elapsed_ms: d.elapsed.as_secs_f64() * 1e3,
            ambiguous: e.is_ambiguous(),
            runner_up: d.runner_up.as_ref().map(|r| {
                let t = r.transform.translation.vector;
                RunnerUpReport {
                    rotation_wxyz: quaternion_wxyz(&r.transform.rotation),
                    translation: [t.x, t.y, t.z],
                    n_inliers: r.inliers.len(),
                }
            }),
            points_checksum: swarmpose_data::register_report::points_checksum(data),
            inliers: &e.inliers,
        }
    }
}

/// The message and exit status of an estimator error on input `name`.
pub fn estimation_error(name: &str, method: Method, e: &PoseError) -> CliError {
    match e {
        // Options are checked when parsed; a config the core still rejects is usage.
        PoseError::InvalidConfig(_) => CliError::usage(format!("{}: {e}", method.name())),
        // The data ran and no pose had enough support: a failed run, not bad input.
        PoseError::InsufficientSupport { .. } => {
            CliError::failure(format!("{name}: {}: {e}", method.name()))
        }
        // Too few, degenerate or non-finite points: the input cannot determine a pose.
        PoseError::TooFewPoints { .. }
        | PoseError::Degenerate { .. }
        | PoseError::NonFinite { .. }
        | PoseError::TooLarge { .. }
        | PoseError::LengthMismatch { .. } => {
            CliError::usage(format!("{name}: {}: {e}", method.name()))
        }
    }
}

/// Exit status 2 for a destination that is a mirror image of the source: no rotation
/// explains it (`dst = -src` answered exit 0 with an inlier RMS nine times its threshold).
///
/// # Errors
/// The usage error naming the input and both fits.
pub fn refuse_mirror_image(name: &str, data: &Correspondences) -> Result<(), CliError> {
    match swarmpose_core::arun::mirror_image(data.src(), data.dst()) {
        None => Ok(()),
        Some(m) => Err(CliError::usage(format!(
            "{name}: the destination points are a mirror image of the source (a reflection \
             fits them with an RMS of {:.3e}, the best rotation {:.3e}): a reflection is not \
             a rigid motion; check the sign of an axis",
            m.rms_reflection, m.rms_rotation
        ))),
    }
}

/// Runs `register`: read, estimate, print one JSON line.
///
/// # Errors
/// Bad options, unreadable or malformed input, an estimator error (all naming the input
/// where they concern it), or standard output that cannot be written.
pub fn run(args: &RegisterArgs) -> Result<(), CliError> {
    // Options first: a bad option is reported before any input is read.
    let estimator = build(args.method, &args.options)?;
    let name = display_name(&args.input);
    let data = read_correspondences(&args.input)?;
    refuse_mirror_image(&name, &data)?;
    let estimate = estimator
        .estimate_seeded(&data, args.seed)
        .map_err(|e| estimation_error(&name, args.method, &e))?;
    let report = Report::new(estimator.name(), &name, args.seed, &data, &estimate);
    let line = serde_json::to_string(&report)
        .map_err(|e| CliError::failure(format!("cannot encode the result as JSON: {e}")))?;
    crate::streams::out(&line)
}
