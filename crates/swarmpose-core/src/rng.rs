//! The seeded random generator used by every stochastic part of the core.

use rand::SeedableRng;

/// The random generator every estimator takes: ChaCha8, portable and reproducible
/// across platforms and releases for a given seed.
pub type SeededRng = rand_chacha::ChaCha8Rng;

/// A [`SeededRng`] from a 64-bit seed.
#[must_use]
pub fn seeded(seed: u64) -> SeededRng {
    SeededRng::seed_from_u64(seed)
}
