//! The figures `cagerig bench` reports — a timing statistic, one model's rows and its report —
//! and the timing helpers the bench passes share (`commands/bench.rs`, `bench_events`,
//! `bench_green`, `bench_table`).

use std::time::Instant;

use serde::Serialize;

#[derive(Debug, Clone, Copy, Serialize)]
pub(crate) struct Stat {
    pub median_ms: f64,
    pub min_ms: f64,
    pub max_ms: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub bytes_moved: Option<u64>,
}

impl Stat {
    pub(crate) fn with_bytes(mut self, bytes: u64) -> Self {
        self.bytes_moved = Some(bytes);
        self
    }
}

#[derive(Debug, Serialize)]
pub(crate) struct ModelRow {
    pub model: String,
    pub vertices: usize,
    pub joints: usize,
    pub cage_vertices: usize,
    pub peak_memory_mb: f64,
    /// Precision of the session-level figures (the `_f32` kernels are the f32 variants).
    pub precision: &'static str,
    pub mvc: Stat,
    pub maxvol: Stat,
    /// ln |det Φ̃| of the selected MaxVol rows (larger is better; shows quality regressions).
    pub maxvol_log_abs_det: f64,
    pub skelup_preprocess: Stat,
    pub cageup_preprocess: Stat,
    pub cor_centres: Stat,
    pub cor_centres_method: String,
    pub cagerev_refactor: Stat,
    pub lbs: Stat,
    pub dqs: Stat,
    pub cor: Stat,
    pub animation_frame: Stat,
    /// CageUp's fit in the timed session.
    pub cage_fit: cagerig::CageFitKind,
    /// How well C' follows the body along the synthetic animation: the worst spread, deviation
    /// and flipped share over 20 evenly spaced frames (not timed).
    pub animation_cage_quality: Option<cagerig::cage_quality::CageQuality>,
    pub rest_cage_drag: Stat,
    pub grab_after_skeleton_edit: Stat,
    /// The drag and the grab with Φ stored in f32 (`--coords-precision f32`).
    pub rest_cage_drag_f32_coords: Stat,
    pub grab_after_skeleton_edit_f32_coords: Stat,
    /// The drag and the grab on the f32 display path (what the editor runs: M and M' drawn in
    /// f32, the exact state kept on CageUp's MaxVol rows).
    pub rest_cage_drag_display: Stat,
    pub grab_after_skeleton_edit_display: Stat,
    pub lbs_f32: Stat,
    pub dqs_f32: Stat,
    pub cor_f32: Stat,
}

/// One model's figures with the default thread pool and, unless skipped, on one thread.
#[derive(Debug, Serialize)]
pub(crate) struct ModelReport {
    #[serde(flatten)]
    pub row: ModelRow,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub one_thread: Option<ModelRow>,
    /// This machine's memory read bandwidth (GB/s) on the default pool, measured once after the
    /// models ([`crate::bench_bandwidth`]), to set the rows' implied bandwidth against.
    pub read_bandwidth_gbs: f64,
    /// The same on one thread, unless that pass is skipped.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub read_bandwidth_gbs_one_thread: Option<f64>,
}

/// Runs `f` `warmup` times untimed, then `reps` times; returns median/min/max in ms.
pub(crate) fn time(reps: usize, warmup: usize, mut f: impl FnMut()) -> Stat {
    for _ in 0..warmup {
        f();
    }
    let mut samples: Vec<f64> = (0..reps.max(1))
        .map(|_| {
            let t = Instant::now();
            f();
            t.elapsed().as_secs_f64() * 1e3
        })
        .collect();
    samples.sort_by(f64::total_cmp);
    Stat {
        median_ms: samples[samples.len() / 2],
        min_ms: samples[0],
        max_ms: samples[samples.len() - 1],
        bytes_moved: None,
    }
}

/// Peak resident memory of this process (VmHWM), in MB; 0 where unknown.
pub(crate) fn peak_memory_mb() -> f64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("VmHWM:"))
                .and_then(|l| l.split_whitespace().nth(1))
                .and_then(|kb| kb.parse::<f64>().ok())
        })
        .map_or(0.0, |kb| kb / 1024.0)
}
