//! The progress bar of the automatic weights (`cagerig weights`, `--auto-weights` on every rig
//! command): it appears once the computation has run for a second, on a terminal only.

use std::io::IsTerminal;
use std::sync::Mutex;
use std::time::{Duration, Instant};

use cagerig::auto_weights::{Progress, Stage};
use indicatif::{ProgressBar, ProgressStyle};

/// A progress bar that appears once the computation has run for a second (on a terminal).
pub struct DelayedBar {
    start: Instant,
    bar: Mutex<Option<ProgressBar>>,
    enabled: bool,
}

impl DelayedBar {
    pub fn new() -> Self {
        Self {
            start: Instant::now(),
            bar: Mutex::new(None),
            enabled: std::io::stderr().is_terminal(),
        }
    }

    pub fn update(&self, p: Progress) {
        if !self.enabled || self.start.elapsed() < Duration::from_secs(1) {
            return;
        }
        let Ok(mut guard) = self.bar.lock() else {
            return;
        };
        let bar = guard.get_or_insert_with(|| {
            let bar = ProgressBar::new(p.total as u64);
            bar.set_style(
                ProgressStyle::with_template("automatic weights: {msg} {bar:40} {pos}/{len}")
                    .unwrap_or_else(|_| ProgressStyle::default_bar()),
            );
            bar
        });
        let stage = match p.stage {
            Stage::Voxelising => "voxelising",
            Stage::Distances => "geodesic distances (joints)",
            Stage::Weights => "weights",
        };
        bar.set_message(stage);
        bar.set_length(p.total as u64);
        bar.set_position(p.done as u64);
    }

    pub fn finish(&self) {
        if let Ok(mut guard) = self.bar.lock()
            && let Some(bar) = guard.take()
        {
            bar.finish_and_clear();
        }
    }
}
