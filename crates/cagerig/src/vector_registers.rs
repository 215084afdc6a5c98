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

#[cfg(test)]
mod tests {
    use faer::Mat;

    use super::*;
    use crate::cage_coords::CageCoords;

    /// Clears so far on the calling thread and on each thread of the pool.
    fn clears() -> (usize, Vec<usize>) {
        (
            CLEARS.with(|c| c.get()),
            rayon::broadcast(|_| CLEARS.with(|c| c.get())),
        )
    }

    #[test]
    fn clearing_leaves_values_alone() {
        let values: Vec<f64> = (0..64).map(f64::from).collect();
        let before: f64 = values.iter().sum();
        clear_upper_halves_everywhere();
        assert_eq!(values.iter().sum::<f64>(), before);
    }

    /// Regression: after MaxVol, SkelUp ran 2× slower on the same threads (36 against 70–75 ms
    /// at Arm N = 3) until a `vzeroupper`. The effect is a speed, measured by the
    /// `skelup_bench` example (Ψ before and after MaxVol); this checks that MaxVol clears the
    /// registers on the calling thread and on every thread of the pool before it returns.
    #[test]
    fn maxvol_clears_every_thread() {
        let (rows, cols) = (4000, 48);
        let matrix = Mat::<f64>::from_fn(rows, cols, |i, k| {
            let x = ((i * 7919 + k * 104_729) % 1009) as f64 / 1009.0;
            x + if i % cols == k { 2.0 } else { 0.0 }
        });
        let phi = CageCoords::from_matrix(matrix).unwrap();
        let (caller, workers) = clears();
        crate::coords::maxvol::select_maxvol_rows(&phi).unwrap();
        let (caller_after, workers_after) = clears();
        assert!(caller_after > caller, "calling thread");
        assert!(
            workers.iter().zip(&workers_after).all(|(a, b)| b > a),
            "{workers:?} → {workers_after:?}"
        );
    }
}
