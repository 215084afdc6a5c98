//! Clearing the upper halves of the vector registers after faer's dense kernels.
//!
//! faer's matrix products and factorisations run AVX-512 micro-kernels (the `gemm` crate) that
//! return with the upper halves of the vector registers still marked in use. Until a
//! `vzeroupper`, every legacy-SSE instruction on that thread pays for it — and most of this
//! crate is compiled for the x86-64 baseline (SSE2). Measured on the project machine (AMD EPYC,
//! Arm N = 3): SkelUp's precomputation took 36 ms before MaxVol had run on the same threads and
//! 70–75 ms after, for as long as the process lived; one `vzeroupper` per thread gave back the
//! 36 ms (the `skelup_bench` example measures both). So the entry points that call faer clear
//! the registers before they return, on every thread they ran it on. (The CPU's XINUSE bits do
//! not show this state: they read the same before and after the clearing.)

#![cfg_attr(
    target_arch = "x86_64",
    expect(
        unsafe_code,
        reason = "the register-width probe calls #[target_feature] functions after detection"
    )
)]

/// Clears the upper halves of the vector registers of the calling thread (a no-op without AVX).
#[inline]
pub(crate) fn clear_upper_halves() {
    #[cfg(test)]
    CLEARS.with(|c| c.set(c.get() + 1));
    #[cfg(target_arch = "x86_64")]
    {
        if std::arch::is_x86_feature_detected!("avx") {
            // SAFETY: the CPU supports AVX (checked just above).
            unsafe { zero_upper() }
        }
    }
}

/// [`clear_upper_halves`] on the calling thread and on every thread of the current rayon pool
/// (after faer ran inside rayon tasks).
pub(crate) fn clear_upper_halves_everywhere() {
    rayon::broadcast(|_| clear_upper_halves());
    clear_upper_halves();
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx")]
fn zero_upper() {
    std::arch::x86_64::_mm256_zeroupper();
}

#[cfg(test)]
thread_local! {
    /// Calls of [`clear_upper_halves`] on this thread (tests check the entry points).
    static CLEARS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

/// Clears so far on the calling thread and on each thread of the pool (tests).
#[cfg(test)]
pub(crate) fn clear_counts() -> (usize, Vec<usize>) {
    (
        CLEARS.with(|c| c.get()),
        rayon::broadcast(|_| CLEARS.with(|c| c.get())),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clearing_leaves_values_alone() {
        let values: Vec<f64> = (0..64).map(f64::from).collect();
        let before: f64 = values.iter().sum();
        clear_upper_halves_everywhere();
        assert_eq!(values.iter().sum::<f64>(), before);
    }
}
