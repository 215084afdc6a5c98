//! The machine's memory read bandwidth, measured by `cagerig bench` beside its rows so that the
//! bandwidth each per-event row implies can be set against it within the same run (the host's
//! speed drifts between runs): a plain streaming sum over a buffer far larger than the caches,
//! on the current rayon pool.

use std::time::Instant;

use rayon::prelude::*;

/// Bytes summed per measurement: 256 MiB, far beyond the caches (32 MiB of L3 on the project
/// machine).
const BUFFER_BYTES: usize = 256 << 20;
/// Measurements; the best is kept.
const REPEATS: usize = 10;
/// Values per rayon task.
const CHUNK: usize = 1 << 16;

/// Best of [`REPEATS`] streaming sums of a 256 MiB buffer of f64 on the current rayon pool, in
/// GB/s (10⁹ bytes per second).
pub(crate) fn read_bandwidth_gbs() -> f64 {
    let values = vec![1.0f64; BUFFER_BYTES / 8];
    let mut best = f64::INFINITY;
    for _ in 0..REPEATS {
        let start = Instant::now();
        let sum: f64 = values.par_chunks(CHUNK).map(sum_of).sum();
        let seconds = start.elapsed().as_secs_f64();
        std::hint::black_box(sum);
        best = best.min(seconds);
    }
    BUFFER_BYTES as f64 / best / 1e9
}

/// Σ values, in eight independent running sums (so that the adds do not wait on each other).
fn sum_of(values: &[f64]) -> f64 {
    let mut lanes = [0.0f64; 8];
    let blocks = values.chunks_exact(8);
    let tail: f64 = blocks.remainder().iter().sum();
    for block in blocks {
        for (lane, &v) in lanes.iter_mut().zip(block) {
            *lane += v;
        }
    }
    lanes.iter().sum::<f64>() + tail
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sums_every_value() {
        let values: Vec<f64> = (0..1003).map(f64::from).collect();
        assert_eq!(sum_of(&values), 1002.0 * 1003.0 / 2.0);
        assert_eq!(sum_of(&[]), 0.0);
    }
}
