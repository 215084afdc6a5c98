//! A seeded generator for the unit tests: reproducible values without a dependency.

/// Values uniform in [0, 1) from the xorshift64 sequence of `seed` (non-zero).
pub(crate) fn uniform(seed: u64) -> impl FnMut() -> f64 {
    let mut state = seed;
    move || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64
    }
}
