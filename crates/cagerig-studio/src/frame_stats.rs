//! Per-frame timings (`--frame-stats`): CPU time of each frame split into the sync of the rig
//! (session events), normals + vertex upload, and the rest of the UI; and the frame time
//! (interval between frame starts).

use std::path::Path;
use web_time::Instant;

use serde::Serialize;

/// Timings of every frame so far.
#[derive(Debug, Default)]
pub struct FrameStats {
    /// Sync milliseconds of the current frame (added to by every session event).
    pub sync_ms: f64,
    /// Upload milliseconds of the current frame (added to by every view).
    pub upload_ms: f64,
    /// Milliseconds recording and submitting GPU work in the current frame.
    pub render_ms: f64,
    frame_start: Option<Instant>,
    previous_start: Option<Instant>,
    sync: Vec<f64>,
    edit: Vec<f64>,
    upload: Vec<f64>,
    render: Vec<f64>,
    ui: Vec<f64>,
    cpu: Vec<f64>,
    interval: Vec<f64>,
}

/// Median and maximum of a series (milliseconds).
#[derive(Debug, Clone, Copy, Serialize, PartialEq)]
pub struct Summary {
    pub median: f64,
    pub max: f64,
}

/// What `--frame-stats` writes.
#[derive(Debug, Clone, Serialize)]
pub struct FrameStatsReport {
    pub frames: usize,
    /// CPU ms in the rig's sync chain (session events: skinning, CageUp, SkelUp, CageRev).
    pub sync_ms: Summary,
    /// CPU ms computing normals and uploading vertex buffers.
    pub normals_upload_ms: Summary,
    /// The CPU part of an edit: sync + normals/upload, per frame (the interactive budget).
    pub sync_and_upload_ms: Summary,
    /// CPU ms recording and submitting the views' GPU work (with a software rasteriser such
    /// as lavapipe this includes drawing the triangles; on a GPU it is small).
    pub render_submit_ms: Summary,
    /// CPU ms in the rest of the frame (UI layout, picking, painting commands).
    pub ui_ms: Summary,
    /// Total CPU ms of the frame (sync + normals/upload + render submission + UI).
    pub cpu_ms: Summary,
    /// Time between the starts of consecutive frames.
    pub frame_time_ms: Summary,
}

fn summary(values: &[f64]) -> Summary {
    if values.is_empty() {
        return Summary {
            median: 0.0,
            max: 0.0,
        };
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let n = v.len();
    let median = if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    };
    Summary {
        median,
        max: v[n - 1],
    }
}

impl FrameStats {
    pub fn begin_frame(&mut self) {
        let now = Instant::now();
        self.previous_start = self.frame_start.replace(now);
        self.sync_ms = 0.0;
        self.upload_ms = 0.0;
        self.render_ms = 0.0;
    }

    /// Ends the frame that took `cpu_ms` of CPU in total.
    pub fn end_frame(&mut self, cpu_ms: f64) {
        self.sync.push(self.sync_ms);
        self.edit.push(self.sync_ms + self.upload_ms);
        self.upload.push(self.upload_ms);
        self.render.push(self.render_ms);
        self.ui
            .push((cpu_ms - self.sync_ms - self.upload_ms - self.render_ms).max(0.0));
        self.cpu.push(cpu_ms);
        if let (Some(a), Some(b)) = (self.previous_start, self.frame_start) {
            self.interval.push((b - a).as_secs_f64() * 1e3);
        }
    }

    pub fn report(&self) -> FrameStatsReport {
        FrameStatsReport {
            frames: self.cpu.len(),
            sync_ms: summary(&self.sync),
            normals_upload_ms: summary(&self.upload),
            sync_and_upload_ms: summary(&self.edit),
            render_submit_ms: summary(&self.render),
            ui_ms: summary(&self.ui),
            cpu_ms: summary(&self.cpu),
            frame_time_ms: summary(&self.interval),
        }
    }

    /// Writes the report as JSON (atomically).
    pub fn write_json(&self, path: &Path) -> Result<(), cagerig::io::ParseError> {
        let text = serde_json::to_string_pretty(&self.report())
            .unwrap_or_else(|e| format!("{{\"error\": \"{e}\"}}"));
        cagerig::io::write_atomically(path, |w| w.write_all(text.as_bytes()))
    }

    /// Milliseconds of the last frame's CPU time, if any.
    pub fn last_cpu_ms(&self) -> Option<f64> {
        self.cpu.last().copied()
    }

    /// Milliseconds between the last two frame starts, if any.
    pub fn last_frame_ms(&self) -> Option<f64> {
        self.interval.last().copied()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summaries_give_median_and_max() {
        assert_eq!(
            summary(&[3.0, 1.0, 2.0]),
            Summary {
                median: 2.0,
                max: 3.0
            }
        );
        assert_eq!(summary(&[4.0, 1.0, 2.0, 3.0]).median, 2.5);
        assert_eq!(summary(&[]).max, 0.0);
    }

    #[test]
    fn the_ui_share_is_the_rest_of_the_cpu_time() {
        let mut s = FrameStats::default();
        s.begin_frame();
        s.sync_ms = 2.0;
        s.upload_ms = 1.0;
        s.end_frame(5.0);
        s.begin_frame();
        s.end_frame(1.0);
        let r = s.report();
        assert_eq!(r.frames, 2);
        assert_eq!(r.ui_ms.max, 2.0);
        assert_eq!(r.sync_ms.max, 2.0);
        assert_eq!(r.cpu_ms.median, 3.0);
        assert!(r.frame_time_ms.median >= 0.0);
    }
}
