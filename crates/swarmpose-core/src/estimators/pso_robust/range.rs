//! Step 5a of [`super`]: the noise model of plain coordinates, chosen by evidence
//! ([`crate::estimators::ray_noise`]).

use rand::seq::index::sample;

use super::{Found, PsoEstimator};
use crate::estimators::RangeNoise;
use crate::estimators::ray_noise;
use crate::geometry::Correspondences;
use crate::rng::SeededRng;

/// Rows the range-dependent noise model is chosen and fitted on (a random sample of
/// larger sets).
const MODEL_ROWS: usize = 2000;

/// Plain coordinates with the covariances of the range-dependent noise model their
/// residuals chose, and the model ([`ray_noise`]); `None` for isotropic noise.
pub(super) type Modelled = Option<(Correspondences, RangeNoise)>;

impl PsoEstimator {
    /// Plain coordinates tested at a uniform δ: the points with the covariances of the
    /// range-dependent noise model ([`ray_noise`]) when the evidence prefers it to
    /// isotropic noise, else `None`.
    pub(super) fn range_model(
        &self,
        data: &Correspondences,
        found: &Found,
        delta: f64,
        rng: &mut SeededRng,
    ) -> Modelled {
        if !self.config.range_noise || data.noise_sigma().is_some() {
            return None;
        }
        let sigma = delta / self.config.sigma_multiplier;
        // A few thousand rows tell the model's three parameters apart; a random sample
        // of larger sets keeps the cost bounded.
        let noise = if data.len() > MODEL_ROWS {
            let mut rows = sample(rng, data.len(), MODEL_ROWS).into_vec();
            rows.sort_unstable();
            ray_noise::choose(&data.select(&rows), &found.pose, delta, sigma)?
        } else {
            ray_noise::choose(data, &found.pose, delta, sigma)?
        };
        let cov = |p: &[nalgebra::Point3<f64>]| p.iter().map(|q| noise.covariance(q)).collect();
        let sigma = data
            .src()
            .iter()
            .zip(data.dst())
            .map(|(s, d)| (noise.largest_variance(s) + noise.largest_variance(d)).sqrt())
            .collect();
        let modelled =
            data.clone()
                .with_trusted_noise_covariance(cov(data.src()), cov(data.dst()), sigma)?;
        Some((modelled, noise))
    }
}
