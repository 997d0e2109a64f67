//! Deterministic noise for the unit tests: one linear congruential generator (the
//! constants of Numerical Recipes), so that every test's pseudo-random image is
//! reproducible without a random-number crate.

/// A 32-bit linear congruential generator: `s <- 1664525 s + 1013904223 (mod 2^32)`.
pub(crate) struct Lcg(pub(crate) u32);

impl Lcg {
    /// The next state.
    pub(crate) fn next_u32(&mut self) -> u32 {
        self.0 = self.0.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
        self.0
    }
}

/// `n` bytes of noise from `seed`: the top 8 bits of each state.
pub(crate) fn noise_bytes(n: usize, seed: u32) -> Vec<u8> {
    let mut g = Lcg(seed);
    (0..n).map(|_| (g.next_u32() >> 24) as u8).collect()
}
