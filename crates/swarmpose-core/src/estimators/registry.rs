//! The one list of estimators by name, used by `register`, `bench` and the simulation:
//! a new estimator joins by adding a [`Method`] here.

use super::{
    Estimator, MsacConfig, MsacEstimator, PsoEstimator, PsoEstimatorConfig, PsoPaperConfig,
    PsoPaperEstimator, SvdEstimator, WlsEstimator,
};
use crate::settings::InvalidSetting;

/// An estimator of the project, by its command-line name.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Method {
    /// `pso`: robust PSO over unit quaternions on translation-free pairs, then SVD
    /// refinement ([`PsoEstimator`]).
    Pso,
    /// `pso-paper`: the paper's PSO/SVD, literally ([`PsoPaperEstimator`]).
    PsoPaper,
    /// `svd`: Arun's SVD on all points ([`SvdEstimator`]).
    Svd,
    /// `msac`: MSAC with 3-point samples ([`MsacEstimator`]).
    Msac,
    /// `wls`: weighted least squares on all points, Mahalanobis with covariances
    /// ([`WlsEstimator`]).
    Wls,
}

impl Method {
    /// Every method, in table order.
    pub const ALL: [Method; 5] = [
        Method::Pso,
        Method::PsoPaper,
        Method::Svd,
        Method::Msac,
        Method::Wls,
    ];

    /// The command-line name, equal to the estimator's [`Estimator::name`].
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            Method::Pso => "pso",
            Method::PsoPaper => "pso-paper",
            Method::Svd => "svd",
            Method::Msac => "msac",
            Method::Wls => "wls",
        }
    }

    /// What the method does, in one line (the command line's help).
    #[must_use]
    pub fn summary(self) -> &'static str {
        match self {
            Method::Pso => {
                "Robust PSO over unit quaternions on translation-free pairs, then SVD refinement"
            }
            Method::PsoPaper => {
                "The paper's PSO/SVD, literally (all-point centroids); fragile with outliers"
            }
            Method::Svd => "Arun's SVD least squares on all points, no outlier rejection",
            Method::Msac => "MSAC with 3-point samples and a final SVD refit",
            Method::Wls => {
                "Weighted least squares on all points (Mahalanobis with covariances), no outlier \
                 rejection"
            }
        }
    }

    /// The method of a command-line name.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Method> {
        Method::ALL.into_iter().find(|m| m.name() == name)
    }

    /// Whether the method takes an inlier threshold (`svd` and `wls` fit every point).
    #[must_use]
    pub fn uses_threshold(self) -> bool {
        matches!(self, Method::Pso | Method::PsoPaper | Method::Msac)
    }

    /// The estimator with its default settings and, for methods that take one, the
    /// threshold δ (metres; `None` keeps the default: automatic for `pso`).
    #[must_use]
    pub fn build(self, threshold_m: Option<f64>) -> Box<dyn Estimator> {
        let mut config = EstimatorConfig::of(self);
        if let Some(d) = threshold_m {
            config = match config {
                EstimatorConfig::Pso(c) => EstimatorConfig::Pso(c.with_threshold(d)),
                EstimatorConfig::PsoPaper(c) => EstimatorConfig::PsoPaper(c.with_threshold(d)),
                EstimatorConfig::Msac(c) => EstimatorConfig::Msac(c.with_threshold(d)),
                other => other,
            };
        }
        config.build()
    }
}

/// An estimator with all its settings: what a run configuration records. In a
/// configuration file, `{"method": "pso", ...the settings of PsoEstimatorConfig}`.
#[derive(Debug, Clone, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(tag = "method", rename_all = "kebab-case")
)]
pub enum EstimatorConfig {
    /// [`Method::Pso`].
    Pso(PsoEstimatorConfig),
    /// [`Method::PsoPaper`].
    PsoPaper(PsoPaperConfig),
    /// [`Method::Svd`] (no settings).
    Svd,
    /// [`Method::Msac`].
    Msac(MsacConfig),
    /// [`Method::Wls`] (no settings).
    Wls,
}

impl Default for EstimatorConfig {
    /// The robust PSO with its default settings.
    fn default() -> Self {
        Self::of(Method::Pso)
    }
}

impl EstimatorConfig {
    /// `method` with its default settings.
    #[must_use]
    pub fn of(method: Method) -> Self {
        match method {
            Method::Pso => Self::Pso(PsoEstimatorConfig::default()),
            Method::PsoPaper => Self::PsoPaper(PsoPaperConfig::default()),
            Method::Svd => Self::Svd,
            Method::Msac => Self::Msac(MsacConfig::default()),
            Method::Wls => Self::Wls,
        }
    }

    /// The method.
    #[must_use]
    pub fn method(&self) -> Method {
        match self {
            Self::Pso(_) => Method::Pso,
            Self::PsoPaper(_) => Method::PsoPaper,
            Self::Svd => Method::Svd,
            Self::Msac(_) => Method::Msac,
            Self::Wls => Method::Wls,
        }
    }

    /// Checks the range of every setting, naming each below `prefix` (`estimator`) as in
    /// a run configuration, before any estimate (each estimator checks its settings
    /// again when it runs).
    ///
    /// # Errors
    /// [`InvalidSetting`] naming the first setting out of its range.
    pub fn check(&self, prefix: &str) -> Result<(), InvalidSetting> {
        match self {
            Self::Pso(c) => c.check(prefix),
            Self::PsoPaper(c) => c.check(prefix),
            Self::Msac(c) => c.check(prefix),
            Self::Svd | Self::Wls => Ok(()),
        }
    }

    /// The estimator.
    #[must_use]
    pub fn build(&self) -> Box<dyn Estimator> {
        match self {
            Self::Pso(c) => Box::new(PsoEstimator::new(c.clone())),
            Self::PsoPaper(c) => Box::new(PsoPaperEstimator::new(c.clone())),
            Self::Svd => Box::new(SvdEstimator),
            Self::Msac(c) => Box::new(MsacEstimator::new(c.clone())),
            Self::Wls => Box::new(WlsEstimator),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_round_trip_and_match_the_estimators() {
        for m in Method::ALL {
            assert_eq!(Method::from_name(m.name()), Some(m));
            assert_eq!(m.build(None).name(), m.name());
            assert_eq!(m.build(Some(0.1)).name(), m.name());
            assert_eq!(EstimatorConfig::of(m).method(), m);
        }
        assert_eq!(Method::from_name("nope"), None);
    }
}
