//! Scripted runs (tests and reproducible figures): `--script` edit scripts through the
//! document's command path, `--screenshot` of the real window, `--quit-after-frames` and
//! `--frame-stats`.

use std::sync::{Arc, Mutex};
use web_time::Instant;

use crate::diagnostics::{Diagnostics, Log};
use crate::document::Document;
use crate::startup::StartupOptions;

/// Runs an edit script file through the document's command path.
pub fn run_script_file(doc: Option<&mut Document>, path: &std::path::Path, log: &mut Log) {
    let text = match std::fs::read_to_string(path) {
        Ok(t) => t,
        Err(e) => {
            log.error(format!("{}: cannot read the script: {e}", path.display()));
            return;
        }
    };
    let script = match cagerig::script::EditScript::parse(&text) {
        Ok(s) => s,
        Err(e) => {
            log.error(format!("{}: {e}", path.display()));
            return;
        }
    };
    let Some(doc) = doc else {
        return;
    };
    let t = Instant::now();
    match doc.run_script(&script) {
        Ok(()) => {
            let n = script.steps.len();
            log.info(format!(
                "script {}: {n} step(s) applied ({:.1} ms)",
                path.display(),
                t.elapsed().as_secs_f64() * 1e3
            ));
        }
        Err(e) => log.error(format!("{}: {e}", path.display())),
    }
}

/// The startup options and the state of a scripted run: frames counted, the screenshot.
pub struct ScriptedRun {
    options: StartupOptions,
    frames: u64,
    screenshot_requested: bool,
    screenshot_done: bool,
    /// Where the screenshot callback puts the window's pixels.
    screenshot_slot: Arc<Mutex<Option<Arc<egui::ColorImage>>>>,
}

impl ScriptedRun {
    pub fn new(options: StartupOptions) -> Self {
        Self {
            options,
            frames: 0,
            screenshot_requested: false,
            screenshot_done: false,
            screenshot_slot: Arc::default(),
        }
    }

    pub fn options(&self) -> &StartupOptions {
        &self.options
    }

    /// Frames counted so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// Runs driven by `--script`, `--screenshot` or `--quit-after-frames` ask no questions.
    pub fn is_scripted(&self) -> bool {
        self.options.script.is_some()
            || self.options.screenshot.is_some()
            || self.options.quit_after_frames.is_some()
    }

    /// Runs that end by themselves (`--screenshot`, `--quit-after-frames`) close without
    /// asking about unsaved edits.
    pub fn ends_by_itself(&self) -> bool {
        self.options.screenshot.is_some() || self.options.quit_after_frames.is_some()
    }

    /// Runs with `--screenshot` or `--script` write no autosave.
    pub fn autosaves(&self) -> bool {
        self.options.screenshot.is_none() && self.options.script.is_none()
    }

    /// Per-frame end: scripted screenshot and quit (or quit as asked: `quit_requested`),
    /// frame statistics.
    pub fn frame_end(&mut self, ctx: &egui::Context, diag: &mut Diagnostics, quit_requested: bool) {
        self.frames += 1;
        let screenshot = self
            .screenshot_slot
            .lock()
            .ok()
            .and_then(|mut slot| slot.take());
        if let (Some(image), Some(path)) = (screenshot, self.options.screenshot.clone()) {
            let rgba = cagerig_render::RgbaImage::new(
                image.size[0] as u32,
                image.size[1] as u32,
                image.pixels.iter().flat_map(|c| c.to_array()).collect(),
            );
            match rgba.write_png(&path) {
                Ok(()) => diag
                    .log
                    .info(format!("screenshot written to {}", path.display())),
                Err(e) => diag.log.error(format!("{}: {e}", path.display())),
            }
            self.screenshot_done = true;
        }
        // Three frames first, so that every view has rendered and egui has laid out.
        if self.options.screenshot.is_some() && !self.screenshot_requested && self.frames >= 3 {
            let slot = Arc::clone(&self.screenshot_slot);
            let repaint = ctx.clone();
            ctx.request_screenshot(move |image| {
                if let Ok(mut s) = slot.lock() {
                    *s = Some(image);
                }
                repaint.request_repaint();
            });
            self.screenshot_requested = true;
        }
        let frames_done = self
            .options
            .quit_after_frames
            .is_some_and(|n| self.frames >= n);
        let screenshot_pending = self.options.screenshot.is_some() && !self.screenshot_done;
        let scripted =
            self.options.screenshot.is_some() || self.options.quit_after_frames.is_some();
        let failed = self.options.failures.lock().is_ok_and(|f| !f.is_empty());
        let scripted_quit = (self.options.screenshot.is_some() && self.screenshot_done)
            || (frames_done && !screenshot_pending)
            || (scripted && failed);
        if scripted_quit || quit_requested {
            self.write_frame_stats(diag);
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        } else if self.options.quit_after_frames.is_some() || screenshot_pending {
            ctx.request_repaint();
        }
    }

    /// Writes the frame statistics of `--frame-stats` (once).
    pub fn write_frame_stats(&mut self, diag: &mut Diagnostics) {
        if let Some(path) = self.options.frame_stats.clone() {
            match diag.stats.write_json(&path) {
                Ok(()) => diag
                    .log
                    .info(format!("frame statistics written to {}", path.display())),
                Err(e) => diag.log.error(format!("{}: {e}", path.display())),
            }
            self.options.frame_stats = None;
        }
    }
}
