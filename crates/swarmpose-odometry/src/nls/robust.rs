//! The robust loss of the solvers: Huber's, on a measurement's squared whitened residual
//! norm `s²`. The cost is `ρ(s²) = s²` up to the threshold `k` on the norm and
//! `2 k s − k²` above (continuous, with a continuous first derivative); the weight of the
//! iteratively reweighted normal equations is `ρ'(s²) = 1` inside and `k / s` above.

/// Huber weight and cost `(w, ρ)` of a squared whitened norm `s2`, threshold `k` on the
/// norm.
#[inline(always)]
pub(crate) fn huber(s2: f64, k: f64) -> (f64, f64) {
    if s2 <= k * k {
        (1.0, s2)
    } else {
        let s = s2.sqrt();
        (k / s, 2.0 * k * s - k * k)
    }
}

/// The Huber weight alone ([`huber`]'s first value).
#[inline(always)]
pub(crate) fn huber_weight(s2: f64, k: f64) -> f64 {
    huber(s2, k).0
}

/// The Huber cost alone ([`huber`]'s second value).
#[inline(always)]
pub(crate) fn huber_cost(s2: f64, k: f64) -> f64 {
    huber(s2, k).1
}
