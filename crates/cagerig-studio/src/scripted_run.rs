//! Scripted runs (tests and reproducible figures): `--script` edit scripts through the
//! document's command path, `--screenshot` of the real window, `--quit-after-frames` and
//! `--frame-stats`.

use std::sync::Arc;
use std::time::Instant;

use crate::app::StudioApp;

impl StudioApp {
    /// Runs driven by `--script`, `--screenshot` or `--quit-after-frames` ask no questions.
    pub fn is_scripted(&self) -> bool {
        self.options.script.is_some()
            || self.options.screenshot.is_some()
            || self.options.quit_after_frames.is_some()
    }

    /// Runs an edit script file through the document's command path.
    pub fn run_script_file(&mut self, path: &std::path::Path) {
        let text = match std::fs::read_to_string(path) {
            Ok(t) => t,
            Err(e) => {
                self.log_error(format!("{}: cannot read the script: {e}", path.display()));
                return;
            }
        };
        let script = match cagerig::script::EditScript::parse(&text) {
            Ok(s) => s,
            Err(e) => {
                self.log_error(format!("{}: {e}", path.display()));
                return;
            }
        };
        let Some(doc) = &mut self.doc else {
            return;
        };
        let t = Instant::now();
        match doc.run_script(&script) {
            Ok(()) => {
                let n = script.steps.len();
                self.log_info(format!(
                    "script {}: {n} step(s) applied ({:.1} ms)",
                    path.display(),
                    t.elapsed().as_secs_f64() * 1e3
                ));
            }
            Err(e) => self.log_error(format!("{}: {e}", path.display())),
        }
    }

    /// Per-frame end: scripted screenshot and quit, frame statistics.
    pub(crate) fn scripted_frame_end(&mut self, ctx: &egui::Context) {
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
                Ok(()) => self.log_info(format!("screenshot written to {}", path.display())),
                Err(e) => self.log_error(format!("{}: {e}", path.display())),
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
        if scripted_quit || self.quit_requested {
            self.write_frame_stats();
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
        } else if self.options.quit_after_frames.is_some() || screenshot_pending {
            ctx.request_repaint();
        }
    }

    pub(crate) fn write_frame_stats(&mut self) {
        if let Some(path) = self.options.frame_stats.clone() {
            match self.stats.write_json(&path) {
                Ok(()) => self.log_info(format!("frame statistics written to {}", path.display())),
                Err(e) => self.log_error(format!("{}: {e}", path.display())),
            }
            self.options.frame_stats = None;
        }
    }
}
