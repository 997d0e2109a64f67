//! The estimators an experiment compares, as name + factory pairs: a new estimator joins
//! by adding an entry here (or passing its own list), never by touching the runner.

use swarmpose_core::{Estimator, Method, MsacConfig, MsacEstimator};

/// Builds an estimator for an inlier threshold δ (metres).
pub type Factory = Box<dyn Fn(f64) -> Box<dyn Estimator> + Send + Sync>;

/// One estimator of an experiment.
pub struct EstimatorEntry {
    /// Name in tables, plots and `runs.csv`.
    pub name: String,
    /// Makes the estimator for a threshold.
    pub make: Factory,
}

impl EstimatorEntry {
    /// An entry from a name and a factory.
    pub fn new(
        name: impl Into<String>,
        make: impl Fn(f64) -> Box<dyn Estimator> + Send + Sync + 'static,
    ) -> Self {
        Self {
            name: name.into(),
            make: Box::new(make),
        }
    }
}

impl std::fmt::Debug for EstimatorEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("EstimatorEntry")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

/// `sqrt(χ²₃(0.99))`: 99 % of 3D Gaussian residuals of σ per axis are below `3.368 σ`.
pub const CHI3_99: f64 = 3.368;

/// Smallest threshold used, metres (for σ = 0).
pub const MIN_THRESHOLD_M: f64 = 0.01;

/// The peers' oracle threshold for noise σ: `max(3.368 σ, 0.01)` metres.
#[must_use]
pub fn oracle_threshold(sigma: f64) -> f64 {
    (CHI3_99 * sigma).max(MIN_THRESHOLD_M)
}

/// Cap on MSAC's samples in experiments (the adaptive count at 90 % outliers is about
/// 7000; the cap only bounds hopeless cases).
pub const MSAC_MAX_ITERATIONS: usize = 20_000;

/// The methods of the core's registry ([`Method`]) that the simulation compares, in
/// table order (`wls` is `svd` on data without a noise model).
pub const SIMULATED: [Method; 4] = [Method::Pso, Method::PsoPaper, Method::Svd, Method::Msac];

/// Every simulated estimator: `pso`, `pso-paper`, `svd`, `msac`, each from the core's
/// registry with its default settings and the given threshold (MSAC's samples capped
/// at [`MSAC_MAX_ITERATIONS`]).
#[must_use]
pub fn default_estimators() -> Vec<EstimatorEntry> {
    SIMULATED
        .into_iter()
        .map(|m| {
            EstimatorEntry::new(m.name(), move |thr| match m {
                Method::Msac => Box::new(MsacEstimator::new(
                    MsacConfig::default()
                        .with_threshold(thr)
                        .with_max_iterations(MSAC_MAX_ITERATIONS),
                )) as Box<dyn Estimator>,
                m => m.build(m.uses_threshold().then_some(thr)),
            })
        })
        .collect()
}
