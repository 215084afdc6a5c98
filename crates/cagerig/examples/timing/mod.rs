//! The repeated wall-clock timing shared by the benchmark examples.

use std::time::Instant;

/// (median, min) wall-clock milliseconds of `reps` runs (at least one), and the last result.
#[expect(clippy::expect_used, reason = "the loop runs at least once")]
pub fn timed<T>(reps: usize, mut f: impl FnMut() -> T) -> ((f64, f64), T) {
    let mut last = None;
    let mut times: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let start = Instant::now();
            last = Some(f());
            start.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    times.sort_by(f64::total_cmp);
    let result = last.expect("at least one run");
    ((times[times.len() / 2], times[0]), result)
}
