//! The estimators by command-line name, and the options that configure them: the one
//! place that maps `--method NAME` plus knobs to a `Box<dyn Estimator>`.
//!
//! Subcommands flatten [`EstimatorOptions`] into their arguments and call [`build`].
//! Defaults shown in `--help` are read from the core's `Default` configurations, so
//! they cannot drift from what runs.

use std::ffi::OsStr;
use std::fmt::Display;
use std::str::FromStr;

use clap::builder::{PossibleValue, PossibleValuesParser, TypedValueParser};
use clap::{Arg, Args, Command};
pub use swarmpose_core::Method;
use swarmpose_core::estimators::MAX_SAMPLES;
use swarmpose_core::pso::{MAX_ITERATIONS, MAX_SWARM_SIZE, PsoConfig};
use swarmpose_core::{
    Estimator, EstimatorConfig, MsacConfig, PsoEstimatorConfig, PsoPaperConfig, Threshold,
};

use crate::error::CliError;

/// `--method NAME`: an estimator of the core's registry ([`Method::ALL`], the one list
/// of names) by its command-line name, each with its [`Method::summary`] in `--help`.
#[derive(Debug, Clone, Copy)]
pub struct MethodParser;

impl TypedValueParser for MethodParser {
    type Value = Method;

    fn parse_ref(
        &self,
        cmd: &Command,
        arg: Option<&Arg>,
        value: &OsStr,
    ) -> Result<Method, clap::Error> {
        let names = PossibleValuesParser::new(Method::ALL.map(|m| m.name()));
        let name = names.parse_ref(cmd, arg, value)?;
        Method::from_name(&name)
            .ok_or_else(|| clap::Error::new(clap::error::ErrorKind::InvalidValue))
    }

    fn possible_values(&self) -> Option<Box<dyn Iterator<Item = PossibleValue> + '_>> {
        let values = Method::ALL.map(|m| PossibleValue::new(m.name()).help(m.summary()));
        Some(Box::new(values.into_iter()))
    }
}

/// Settings of every estimator; an option left out keeps the method's default.
#[derive(Debug, Clone, Default, PartialEq, Args)]
pub struct EstimatorOptions {
    /// Inlier threshold δ on |dst - (R src + t)| (not for svd).
    #[arg(long, value_name = "METRES", value_parser = positive_metres,
          allow_negative_numbers = true, help = threshold_help())]
    pub threshold: Option<f64>,

    /// Swarm size.
    #[arg(long, value_name = "N", value_parser = whole_number(1, MAX_SWARM_SIZE),
          help_heading = PSO_HEADING, allow_negative_numbers = true,
          help = pso_help("Swarm size", |c| c.swarm_size))]
    pub particles: Option<usize>,

    /// Iteration budget after the initial evaluation.
    #[arg(long, value_name = "N", value_parser = whole_number(0, MAX_ITERATIONS),
          help_heading = PSO_HEADING, allow_negative_numbers = true,
          help = pso_help("Iteration budget after the initial evaluation", |c| c.max_iterations))]
    pub iterations: Option<usize>,

    /// Inertia α of the velocity update.
    #[arg(long, value_name = "A", value_parser = non_negative, help_heading = PSO_HEADING,
          allow_negative_numbers = true,
          help = pso_help("Inertia α of the velocity update, >= 0", |c| c.inertia))]
    pub inertia: Option<f64>,

    /// Acceleration c of the cognitive and social terms.
    #[arg(long, value_name = "C", value_parser = non_negative, help_heading = PSO_HEADING,
          allow_negative_numbers = true,
          help = pso_help("Acceleration c of the cognitive and social terms, >= 0", |c| c.acceleration))]
    pub acceleration: Option<f64>,

    /// Stop after N iterations without improvement, or `none`.
    #[arg(long, value_name = "N|none", value_parser = stall, help_heading = PSO_HEADING,
          allow_negative_numbers = true,
          help = pso_help("Stop after N iterations without a better best, or 'none' to run the whole budget",
                          |c| Stall(c.stall_iterations)))]
    pub stall: Option<Stall>,

    /// Particles started from 3-point minimal samples (pso only).
    #[arg(long, value_name = "N", value_parser = whole_number(0, MAX_SWARM_SIZE),
          help_heading = PSO_HEADING, allow_negative_numbers = true, help = format!(
              "Particles started from 3-point minimal samples, pso only [default: {}]",
              PsoEstimatorConfig::default().seeded_particles))]
    pub seeded_particles: Option<usize>,

    /// MSAC confidence that an all-inlier sample was drawn.
    #[arg(long, value_name = "P", value_parser = probability, help_heading = MSAC_HEADING,
          allow_negative_numbers = true, help = format!(
              "Probability that an all-inlier sample was drawn when sampling stops, in (0, 1) [default: {}]",
              MsacConfig::default().confidence))]
    pub confidence: Option<f64>,

    /// Cap on the number of MSAC samples.
    #[arg(long, value_name = "N", value_parser = whole_number(1, MAX_SAMPLES),
          help_heading = MSAC_HEADING, allow_negative_numbers = true, help = format!(
              "Cap on the number of samples [default: {}]",
              MsacConfig::default().max_iterations))]
    pub max_samples: Option<usize>,
}

const PSO_HEADING: &str = "PSO options (pso, pso-paper)";
const MSAC_HEADING: &str = "MSAC options (msac)";

/// `--stall`: `Some(n)` stops after `n` iterations without improvement, `None` never.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Stall(pub Option<usize>);

impl Display for Stall {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self.0 {
            Some(n) => write!(f, "{n}"),
            None => f.write_str("none"),
        }
    }
}

/// `[default: X]` when every method agrees, else `[default: X for a, Y for b]`.
fn default_note<T: Display + PartialEq>(values: &[(&str, T)]) -> String {
    match values {
        [(_, first), rest @ ..] if rest.iter().all(|(_, v)| v == first) => {
            format!("[default: {first}]")
        }
        _ => {
            let parts: Vec<String> = values.iter().map(|(m, v)| format!("{v} for {m}")).collect();
            format!("[default: {}]", parts.join(", "))
        }
    }
}

fn threshold_help() -> String {
    format!(
        "Inlier threshold δ on |dst - (R src + t)|, metres, > 0; svd has none; pso \
         estimates it from the data unless given {}",
        default_note(&[
            ("pso", PsoEstimatorConfig::default().threshold.to_string()),
            (
                "pso-paper",
                PsoPaperConfig::default().threshold_m.to_string()
            ),
            ("msac", MsacConfig::default().threshold_m.to_string()),
        ])
    )
}

fn pso_help<T: Display + PartialEq>(what: &str, field: impl Fn(&PsoConfig) -> T) -> String {
    let note = default_note(&[
        ("pso", field(&PsoEstimatorConfig::default().pso)),
        ("pso-paper", field(&PsoPaperConfig::default().pso)),
    ]);
    format!("{what} {note}")
}

/// `s` as a `T` for which `ok` holds, else the error `message` (clap prints it after the
/// option's name).
fn parse_where<T: FromStr>(
    s: &str,
    ok: impl Fn(&T) -> bool,
    message: impl FnOnce() -> String,
) -> Result<T, String> {
    s.trim().parse::<T>().ok().filter(ok).ok_or_else(message)
}

/// The parser of a whole number from `lo` to `hi` (`--iterations`, `--max-samples`,
/// `--particles`, `--seeded-particles`: bounded work per estimate).
fn whole_number(
    lo: usize,
    hi: usize,
) -> impl Fn(&str) -> Result<usize, String> + Clone + Send + Sync + 'static {
    move |s: &str| {
        parse_where(
            s,
            |n| (lo..=hi).contains(n),
            || format!("must be a whole number from {lo} to {hi}"),
        )
    }
}

fn positive_metres(s: &str) -> Result<f64, String> {
    parse_where(
        s,
        |v: &f64| v.is_finite() && *v > 0.0,
        || "must be a positive, finite number of metres".into(),
    )
}

fn non_negative(s: &str) -> Result<f64, String> {
    parse_where(
        s,
        |v: &f64| v.is_finite() && *v >= 0.0,
        || "must be a finite number >= 0".into(),
    )
}

fn probability(s: &str) -> Result<f64, String> {
    parse_where(
        s,
        |v: &f64| *v > 0.0 && *v < 1.0,
        || "must be a number strictly between 0 and 1".into(),
    )
}

fn at_least_one(s: &str) -> Result<usize, String> {
    parse_where(
        s,
        |n: &usize| *n >= 1,
        || "must be a whole number >= 1".into(),
    )
}

fn stall(s: &str) -> Result<Stall, String> {
    if s.trim().eq_ignore_ascii_case("none") {
        return Ok(Stall(None));
    }
    at_least_one(s)
        .map(|n| Stall(Some(n)))
        .map_err(|_| "must be a whole number >= 1, or 'none' to run the whole budget".into())
}

impl EstimatorOptions {
    /// Names of the PSO options given (all of which apply to pso; all but
    /// `--seeded-particles` to pso-paper).
    fn pso_given(&self) -> Vec<&'static str> {
        let given = [
            ("--particles", self.particles.is_some()),
            ("--iterations", self.iterations.is_some()),
            ("--inertia", self.inertia.is_some()),
            ("--acceleration", self.acceleration.is_some()),
            ("--stall", self.stall.is_some()),
            ("--seeded-particles", self.seeded_particles.is_some()),
        ];
        given.iter().filter(|g| g.1).map(|g| g.0).collect()
    }

    fn msac_given(&self) -> Vec<&'static str> {
        let given = [
            ("--confidence", self.confidence.is_some()),
            ("--max-samples", self.max_samples.is_some()),
        ];
        given.iter().filter(|g| g.1).map(|g| g.0).collect()
    }

    /// The swarm settings: `base` with the given PSO options applied.
    fn apply_pso(&self, mut pso: PsoConfig) -> PsoConfig {
        pso.swarm_size = self.particles.unwrap_or(pso.swarm_size);
        pso.max_iterations = self.iterations.unwrap_or(pso.max_iterations);
        pso.inertia = self.inertia.unwrap_or(pso.inertia);
        pso.acceleration = self.acceleration.unwrap_or(pso.acceleration);
        if let Some(Stall(s)) = self.stall {
            pso.stall_iterations = s;
        }
        pso
    }
}

/// Fails when an option that `method` does not use was given: silently ignoring it
/// would report a run that did not happen.
fn reject(method: Method, options: &[&'static str]) -> Result<(), CliError> {
    match options {
        [] => Ok(()),
        [one] => Err(CliError::usage(format!(
            "{one} does not apply to --method {}",
            method.name()
        ))),
        many => Err(CliError::usage(format!(
            "{} do not apply to --method {}",
            many.join(", "),
            method.name()
        ))),
    }
}

/// The estimator for `method` with `options` applied over its defaults.
///
/// # Errors
/// A usage error when an option given does not apply to `method`.
pub fn build(method: Method, options: &EstimatorOptions) -> Result<Box<dyn Estimator>, CliError> {
    Ok(configure(EstimatorConfig::of(method), options)?.build())
}

/// The settings of `base`'s estimator with `options` applied over them (a run
/// configuration's estimator, or a method's defaults).
///
/// # Errors
/// A usage error when an option given does not apply to the method.
pub fn configure(
    base: EstimatorConfig,
    options: &EstimatorOptions,
) -> Result<EstimatorConfig, CliError> {
    let pso = options.pso_given();
    let msac = options.msac_given();
    let method = base.method();
    Ok(match base {
        EstimatorConfig::Pso(mut config) => {
            reject(method, &msac)?;
            if let Some(d) = options.threshold {
                config.threshold = Threshold::Fixed(d);
            }
            config.pso = options.apply_pso(config.pso);
            config.seeded_particles = options.seeded_particles.unwrap_or(config.seeded_particles);
            EstimatorConfig::Pso(config)
        }
        EstimatorConfig::PsoPaper(mut config) => {
            let not_used: Vec<_> = msac
                .into_iter()
                .chain(options.seeded_particles.map(|_| "--seeded-particles"))
                .collect();
            reject(method, &not_used)?;
            config.threshold_m = options.threshold.unwrap_or(config.threshold_m);
            config.pso = options.apply_pso(config.pso);
            EstimatorConfig::PsoPaper(config)
        }
        base @ (EstimatorConfig::Svd | EstimatorConfig::Wls) => {
            let threshold = options.threshold.map(|_| "--threshold");
            let not_used: Vec<_> = threshold.into_iter().chain(pso).chain(msac).collect();
            reject(method, &not_used)?;
            base
        }
        EstimatorConfig::Msac(mut config) => {
            reject(method, &pso)?;
            config.threshold_m = options.threshold.unwrap_or(config.threshold_m);
            config.confidence = options.confidence.unwrap_or(config.confidence);
            config.max_iterations = options.max_samples.unwrap_or(config.max_iterations);
            EstimatorConfig::Msac(config)
        }
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_match_the_estimators() {
        // Every registry entry is a --method value, parsed back to itself, and names its
        // estimator.
        let cmd = Command::new("t");
        let values: Vec<PossibleValue> = MethodParser.possible_values().expect("listed").collect();
        assert_eq!(values.len(), Method::ALL.len());
        for (m, value) in Method::ALL.into_iter().zip(&values) {
            let e = build(m, &EstimatorOptions::default()).expect("defaults build");
            assert_eq!(e.name(), m.name());
            assert_eq!(value.get_name(), m.name());
            let parsed = MethodParser.parse_ref(&cmd, None, OsStr::new(m.name()));
            assert_eq!(parsed.expect("value name"), m);
        }
        assert!(
            MethodParser
                .parse_ref(&cmd, None, OsStr::new("ransac"))
                .is_err()
        );
    }

    #[test]
    fn default_notes() {
        assert_eq!(default_note(&[("a", 1), ("b", 1)]), "[default: 1]");
        assert_eq!(
            default_note(&[("a", 1), ("b", 2)]),
            "[default: 1 for a, 2 for b]"
        );
    }

    #[test]
    fn parsers_reject_bad_values() {
        assert!(positive_metres("-0.1").is_err());
        assert!(positive_metres("0").is_err());
        assert!(positive_metres("NaN").is_err());
        assert!(positive_metres("inf").is_err());
        assert_eq!(positive_metres("0.05"), Ok(0.05));
        assert!(at_least_one("0").is_err());
        let iterations = whole_number(0, MAX_ITERATIONS);
        assert!(iterations("-1").is_err());
        assert_eq!(iterations("100000"), Ok(100_000));
        assert!(iterations("100001").is_err());
        let samples = whole_number(1, MAX_SAMPLES);
        assert!(samples("0").is_err());
        assert!(samples("1000000000000000000").is_err());
        assert!(probability("1").is_err());
        assert!(probability("NaN").is_err());
        assert!(non_negative("-1").is_err());
        assert_eq!(stall("none"), Ok(Stall(None)));
        assert_eq!(stall("3"), Ok(Stall(Some(3))));
        assert!(stall("0").is_err());
    }

    #[test]
    fn options_that_do_not_apply_are_errors() {
        let opts = EstimatorOptions {
            particles: Some(10),
            threshold: Some(0.2),
            ..Default::default()
        };
        let e = build(Method::Svd, &opts).err().expect("svd has no knobs");
        assert_eq!(
            e.message,
            "--threshold, --particles do not apply to --method svd"
        );
        assert!(build(Method::Msac, &opts).is_err());
        assert!(build(Method::PsoPaper, &opts).is_ok());
        let seeded = EstimatorOptions {
            seeded_particles: Some(3),
            ..Default::default()
        };
        assert!(build(Method::PsoPaper, &seeded).is_err());
        assert!(build(Method::Pso, &seeded).is_ok());
    }
}
