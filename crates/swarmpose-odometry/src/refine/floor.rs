//! The systematic floor of the motion covariance: errors shared at the scale of half the
//! image, which a factor taken from one frame's residuals cannot see (a change of the
//! motion absorbs most of a region's shift, and leaves no residual for it), estimated
//! online from the split-feature check ([`super::split`]) of past frames.
//!
//! Each checked pair gives a sample `d` of the difference of the motions of its two
//! halves, whose covariance under the model is `C = C₁ + C₂`. Whitened by the Cholesky
//! factor of its own covariance, `w = L⁻¹ d` (`C = L Lᵀ`) has the covariance `I` when the
//! covariance is honest and `I + X` when each half carries errors the model leaves out;
//! `X` (dimensionless) is that excess in the motion's own whitened frame. The floor keeps
//! an exponentially weighted mean of `w wᵀ` over the past frames (bounded state: one 6x6
//! matrix and two numbers), and its excess
//!
//! * is **nothing** unless the mean of `|w|²` exceeds 6 by more than `significance`
//!   standard deviations of the mean of as many honest samples (`√(12 / n)` for `n`
//!   effective samples, `|w|²` being χ² with 6 degrees of freedom): where the model is
//!   honest, nothing is added;
//! * otherwise, the mean shrunk toward its scaled identity with the Rao-Blackwellised
//!   Ledoit-Wolf intensity (Chen, Wiesel, Eldar and Hero 2010; a 6x6 matrix from a few
//!   tens of samples is too noisy to be inverted as it is), less `I`, its negative
//!   eigenvalues set to zero.
//!
//! A motion of model covariance `C_m = L_m L_mᵀ` (a pair's, the window's, a split
//! check's) is given `C_m + L_m X L_mᵀ`: the errors the model misses in the same
//! proportion to the ones it counts. For a pair's motion, which is about the mean of its
//! two halves (`C_m ≈ C / 4` and, with errors independent across the halves, a floor of
//! about a quarter of theirs), that is the same `X`. The Cholesky factor scales with the
//! units of each axis (`chol(D C D) = D chol(C)` for a diagonal `D`), so the floor does
//! not depend on units or the scene's size; it is estimated per frame, so it does not
//! depend on the frame rate except through how many frames it remembers. Errors shared
//! by all the features (the whole image's motion) cancel in `d`: the floor cannot see
//! them either.
//!
//! The floor a frame is given is learned from the frames before it only: judged on the
//! frame's own split check, it is judged on a pair it has not seen.

use nalgebra::{Cholesky, Matrix6, SymmetricEigen, Vector6};

use super::split::SplitCheck;

/// Settings of the systematic floor ([`SystematicFloor`]).
#[derive(Debug, Clone, Copy, PartialEq)]
#[cfg_attr(
    feature = "serde",
    derive(serde::Serialize, serde::Deserialize),
    serde(default, deny_unknown_fields)
)]
pub struct FloorConfig {
    /// Add the floor to every covariance the engine reports (default true). It runs the
    /// split-feature check on every refined pair: two more refinements a frame.
    pub enabled: bool,
    /// Frames remembered by the exponentially weighted mean (default 50): the `k`-th
    /// sample is weighed `1 / min(k, memory_frames)`, so the first ones make a plain
    /// mean. At least 1.
    pub memory_frames: usize,
    /// Standard deviations of the mean of honest samples by which the mean normalised
    /// squared difference must exceed 6 before any floor is added (default 2; one-sided,
    /// about 2 % of honest means exceed it).
    pub significance: f64,
}

impl Default for FloorConfig {
    fn default() -> Self {
        Self {
            enabled: true,
            memory_frames: 50,
            significance: 2.0,
        }
    }
}

/// The systematic floor's state: the exponentially weighted mean of the whitened
/// differences' second moments, and the excess it leads to.
#[derive(Debug, Clone, PartialEq)]
pub struct SystematicFloor {
    config: FloorConfig,
    /// Samples taken so far.
    samples: usize,
    /// The weighted mean of `w wᵀ`.
    moment: Matrix6<f64>,
    /// The sum of the squared weights (`1 / n` for `n` effective samples).
    weights_sq: f64,
    /// The excess `X` of the covariance (whitened, dimensionless), positive semidefinite.
    excess: Matrix6<f64>,
}

/// `L` of `c = L Lᵀ`, or `None` when `c` is not positive definite.
fn factor(c: &Matrix6<f64>) -> Option<Matrix6<f64>> {
    Cholesky::new(*c).map(|ch| ch.l())
}

impl SystematicFloor {
    /// A floor that has seen nothing (it adds nothing).
    #[must_use]
    pub fn new(config: FloorConfig) -> Self {
        Self {
            config,
            samples: 0,
            moment: Matrix6::zeros(),
            weights_sq: 0.0,
            excess: Matrix6::zeros(),
        }
    }

    /// Whether it is on ([`FloorConfig::enabled`]).
    #[must_use]
    pub fn enabled(&self) -> bool {
        self.config.enabled
    }

    /// The excess `X` (whitened, dimensionless; zero when nothing is needed).
    #[must_use]
    pub fn excess(&self) -> &Matrix6<f64> {
        &self.excess
    }

    /// Samples taken so far.
    #[must_use]
    pub fn samples(&self) -> usize {
        self.samples
    }

    /// `covariance` (metres and radians, any motion's) with the floor added:
    /// `C + L X Lᵀ`. Unchanged, bit for bit, when the excess is zero or `covariance` is
    /// not positive definite.
    #[must_use]
    pub fn widen(&self, covariance: &Matrix6<f64>) -> Matrix6<f64> {
        if self.excess == Matrix6::zeros() {
            return *covariance;
        }
        let Some(l) = factor(covariance) else {
            return *covariance;
        };
        let added = l * self.excess * l.transpose();
        covariance + (added + added.transpose()) * 0.5
    }

    /// The split check `raw` (under the model's covariance) judged with the floor: its
    /// covariance widened and its NEES recomputed ([`SplitCheck::model_nees`] keeps the
    /// model's).
    #[must_use]
    pub fn judge(&self, raw: &SplitCheck) -> SplitCheck {
        if self.excess == Matrix6::zeros() {
            return *raw;
        }
        let covariance = self.widen(&raw.covariance);
        let nees = Cholesky::new(covariance).map_or(raw.nees, |ch| {
            let w = ch.l().solve_lower_triangular(&raw.difference);
            w.map_or(raw.nees, |w| w.norm_squared())
        });
        SplitCheck {
            covariance,
            nees,
            ..*raw
        }
    }

    /// Takes the split check `raw` (under the model's covariance, before any floor) as
    /// a sample. A check whose covariance is not positive definite or whose difference
    /// is not finite is left out.
    pub fn learn(&mut self, raw: &SplitCheck) {
        let Some(w) = whitened(raw) else {
            return;
        };
        self.samples += 1;
        let alpha = 1.0 / self.samples.min(self.config.memory_frames.max(1)) as f64;
        self.moment = self.moment * (1.0 - alpha) + w * w.transpose() * alpha;
        self.weights_sq = self.weights_sq * (1.0 - alpha).powi(2) + alpha * alpha;
        self.excess = excess_of(
            &self.moment,
            1.0 / self.weights_sq,
            self.config.significance,
        );
    }
}

/// `L⁻¹ d` of a split check (`C₁ + C₂ = L Lᵀ`), when defined and finite.
fn whitened(raw: &SplitCheck) -> Option<Vector6<f64>> {
    let l = factor(&raw.covariance)?;
    let w = l.solve_lower_triangular(&raw.difference)?;
    w.iter().all(|x| x.is_finite()).then_some(w)
}

/// The excess `X` of the mean second moment `moment` of `n` effective whitened samples:
/// zero unless its trace exceeds 6 by `significance` standard deviations of honest
/// means; otherwise the moment shrunk toward `tr / 6 · I` (Rao-Blackwellised
/// Ledoit-Wolf), less `I`, projected onto the positive semidefinite matrices.
#[must_use]
pub fn excess_of(moment: &Matrix6<f64>, n: f64, significance: f64) -> Matrix6<f64> {
    const P: f64 = 6.0;
    let tr = moment.trace();
    if !tr.is_finite() || tr <= P + significance * (2.0 * P / n).sqrt() {
        return Matrix6::zeros();
    }
    let tr_sq = (moment * moment).trace();
    let spread = tr_sq - tr * tr / P;
    let rho = if spread > 0.0 && n > 2.0 {
        (((n - 2.0) / n * tr_sq + tr * tr) / ((n + 2.0) * spread)).min(1.0)
    } else {
        1.0
    };
    let shrunk = moment * (1.0 - rho) + Matrix6::identity() * (rho * tr / P);
    let eig = SymmetricEigen::new((shrunk + shrunk.transpose()) * 0.5 - Matrix6::identity());
    let clipped = eig.eigenvalues.map(|x| x.max(0.0));
    let x = eig.eigenvectors * Matrix6::from_diagonal(&clipped) * eig.eigenvectors.transpose();
    (x + x.transpose()) * 0.5
}
