//! The status bar (sync time of the last event, frame time, counts, undo depth) and the log
//! panel where load warnings and errors are shown.

use crate::diagnostics::{Diagnostics, LogLevel};
use crate::document::Document;
use crate::selection::Selection;

/// The bottom status bar and, above it, the log panel (collapsible). The Shortcuts button
/// sets `show_shortcuts`.
pub fn status_bar_ui(
    ui: &mut egui::Ui,
    doc: Option<&Document>,
    selection: &Selection,
    diag: &Diagnostics,
    show_shortcuts: &mut bool,
) {
    egui::Panel::bottom("status").show(ui, |ui| {
        ui.horizontal(|ui| {
            match doc {
                Some(doc) => {
                    let s = &doc.session;
                    ui.label(format!(
                        "sync {:.2} ms | frame {} | {} vertices, {} joints, {} cage vertices | \
                         {} | undo {} / redo {}",
                        doc.last_sync_ms,
                        diag.stats
                            .last_frame_ms()
                            .map_or_else(|| "–".to_string(), |f| format!("{f:.1} ms")),
                        s.num_vertices(),
                        if doc.rigged() { s.skeleton().len() } else { 0 },
                        s.rest_cage().len(),
                        s.skinning().label(),
                        doc.history().undo_len(),
                        doc.history().redo_len(),
                    ));
                    let n = selection.cage.len();
                    if n > 0 {
                        ui.label(format!("| {n} cage vertices selected"));
                    }
                    if let Some(name) = selection
                        .joint
                        .and_then(|j| doc.shown_skeleton(true).names.get(j).cloned())
                    {
                        ui.label(format!("| joint {name}"));
                    }
                }
                None => {
                    ui.label("no rig open");
                }
            }
            ui.with_layout(egui::Layout::right_to_left(egui::Align::Center), |ui| {
                if ui.small_button("Shortcuts").clicked() {
                    *show_shortcuts = true;
                }
            });
        });
    });
    let errors = diag.log.count(LogLevel::Error);
    let warnings = diag.log.count(LogLevel::Warning);
    egui::Panel::bottom("log")
        .resizable(false)
        .exact_size(84.0)
        .show(ui, |ui| {
            ui.label(format!("Log ({errors} errors, {warnings} warnings)"));
            egui::ScrollArea::vertical()
                .auto_shrink([false, false])
                .stick_to_bottom(true)
                .show(ui, |ui| {
                    for line in &diag.log {
                        let color = match line.level {
                            LogLevel::Info => ui.visuals().text_color(),
                            LogLevel::Warning => egui::Color32::from_rgb(200, 140, 0),
                            LogLevel::Error => egui::Color32::from_rgb(220, 40, 40),
                        };
                        ui.colored_label(color, &line.text);
                    }
                });
        });
}
