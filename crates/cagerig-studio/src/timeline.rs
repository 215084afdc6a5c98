//! The timeline: a skeleton track and a cage track with their keys, play / pause / loop /
//! speed, scrubbing, and key selection, moving and deletion.

use crate::app::StudioApp;
use crate::document::Command;
use crate::keys::Track;

/// Playback state.
#[derive(Debug, Clone)]
pub struct TimelineState {
    /// Current time (seconds).
    pub time: f64,
    pub playing: bool,
    pub looping: bool,
    /// Playback speed (1 = real time).
    pub speed: f64,
    /// Selected key.
    pub selected: Option<(Track, usize)>,
    /// A key being dragged: (track, index, time under the mouse).
    dragging: Option<(Track, usize, f64)>,
}

impl Default for TimelineState {
    fn default() -> Self {
        Self {
            time: 0.0,
            playing: false,
            looping: true,
            speed: 1.0,
            selected: None,
            dragging: None,
        }
    }
}

const TRACK_HEIGHT: f32 = 22.0;
const LABEL_WIDTH: f32 = 70.0;

impl StudioApp {
    /// Runs a command as one undo step, logging a failure.
    pub fn run_command(&mut self, command: &Command) -> bool {
        let Some(doc) = &mut self.doc else {
            return false;
        };
        match doc.execute(command) {
            Ok(()) => {
                self.stats.sync_ms += doc.last_sync_ms;
                true
            }
            Err(e) => {
                self.log_error(format!("{}: {e}", command.label()));
                false
            }
        }
    }

    /// Moves the playhead and samples the keys there.
    pub fn scrub_to(&mut self, time: f64) {
        self.timeline.time = time.max(0.0);
        let Some(doc) = &mut self.doc else { return };
        match doc.sample(self.timeline.time) {
            Ok(_) => self.stats.sync_ms += doc.last_sync_ms,
            Err(e) => self.log_error(format!("sampling the keys: {e}")),
        }
    }

    /// Keys the current pose or rest cage at the playhead.
    pub fn set_key(&mut self, track: Track) {
        let time = self.timeline.time;
        if self.run_command(&Command::SetKey { track, time })
            && let Some(doc) = &self.doc
        {
            self.timeline.selected = doc.keys.index_at(track, time).map(|i| (track, i));
        }
    }

    /// Deletes the selected key.
    pub fn delete_selected_key(&mut self) {
        if let Some((track, index)) = self.timeline.selected.take() {
            self.run_command(&Command::DeleteKey { track, index });
        }
    }
}

/// The bottom panel with the transport and the two tracks.
pub fn timeline_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    egui::Panel::bottom("timeline")
        .resizable(false)
        .show(ui, |ui| {
            transport_ui(app, ui);
            tracks_ui(app, ui);
        });
}

fn transport_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    ui.horizontal(|ui| {
        let play_label = if app.timeline.playing {
            "Pause"
        } else {
            "Play"
        };
        if ui.button(play_label).on_hover_text("Space").clicked() {
            app.toggle_play();
        }
        if ui.button("Rewind").on_hover_text("Back to 0 s").clicked() {
            app.scrub_to(0.0);
        }
        ui.checkbox(&mut app.timeline.looping, "Loop");
        ui.label("Speed");
        ui.add(
            egui::DragValue::new(&mut app.timeline.speed)
                .range(0.05..=8.0)
                .speed(0.01)
                .suffix("×"),
        );
        ui.label("Time");
        let mut t = app.timeline.time;
        if ui
            .add(
                egui::DragValue::new(&mut t)
                    .range(0.0..=3600.0)
                    .speed(0.01)
                    .suffix(" s"),
            )
            .changed()
        {
            app.scrub_to(t);
        }
        ui.separator();
        if ui
            .button("Key skeleton")
            .on_hover_text("K: key the current pose S'")
            .clicked()
        {
            app.set_key(Track::Skeleton);
        }
        if ui
            .button("Key cage")
            .on_hover_text("Shift+K: key the rest cage C")
            .clicked()
        {
            app.set_key(Track::Cage);
        }
        let has_selection = app.timeline.selected.is_some();
        if ui
            .add_enabled(has_selection, egui::Button::new("Delete key"))
            .clicked()
        {
            app.delete_selected_key();
        }
    });
}

fn tracks_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    let Some(doc) = &app.doc else { return };
    let skeleton_times: Vec<f64> = doc.keys.skeleton.iter().map(|k| k.time).collect();
    let cage_times: Vec<f64> = doc.keys.cage.iter().map(|k| k.time).collect();
    let span = (doc.keys.duration().max(app.timeline.time) + 1.0).max(2.0);
    let width = ui.available_width();
    let (rect, response) = ui.allocate_exact_size(
        egui::vec2(width, 2.0 * TRACK_HEIGHT + 14.0),
        egui::Sense::click_and_drag(),
    );
    let painter = ui.painter_at(rect);
    let x0 = rect.left() + LABEL_WIDTH;
    let x1 = rect.right() - 8.0;
    let to_x = |t: f64| x0 + (x1 - x0) * (t / span) as f32;
    let to_t = |x: f32| (f64::from((x - x0) / (x1 - x0).max(1.0)) * span).max(0.0);
    let visuals = ui.visuals();
    painter.rect_filled(rect, 2.0, visuals.extreme_bg_color);
    // Ruler.
    let step = if span > 20.0 {
        5.0
    } else if span > 6.0 {
        1.0
    } else {
        0.5
    };
    let mut t = 0.0;
    while t <= span {
        let x = to_x(t);
        painter.line_segment(
            [egui::pos2(x, rect.top()), egui::pos2(x, rect.top() + 4.0)],
            egui::Stroke::new(1.0, visuals.weak_text_color()),
        );
        painter.text(
            egui::pos2(x + 2.0, rect.top()),
            egui::Align2::LEFT_TOP,
            format!("{t}"),
            egui::FontId::proportional(9.0),
            visuals.weak_text_color(),
        );
        t += step;
    }
    let rows = [
        (Track::Skeleton, "skeleton", &skeleton_times),
        (Track::Cage, "cage", &cage_times),
    ];
    let row_y = |r: usize| rect.top() + 14.0 + TRACK_HEIGHT * (r as f32 + 0.5);
    let mut hovered_key: Option<(Track, usize)> = None;
    let pointer = response.hover_pos();
    for (r, (track, name, times)) in rows.iter().enumerate() {
        let y = row_y(r);
        painter.text(
            egui::pos2(rect.left() + 6.0, y),
            egui::Align2::LEFT_CENTER,
            *name,
            egui::FontId::proportional(12.0),
            visuals.text_color(),
        );
        painter.line_segment(
            [egui::pos2(x0, y), egui::pos2(x1, y)],
            visuals.widgets.noninteractive.bg_stroke,
        );
        for (i, &kt) in times.iter().enumerate() {
            let dragged = app
                .timeline
                .dragging
                .filter(|&(dt, di, _)| dt == *track && di == i)
                .map(|(_, _, t)| t);
            let x = to_x(dragged.unwrap_or(kt));
            let centre = egui::pos2(x, y);
            let selected = app.timeline.selected == Some((*track, i));
            let color = match (selected, track) {
                (true, _) => egui::Color32::from_rgb(255, 200, 40),
                (false, Track::Skeleton) => egui::Color32::from_rgb(80, 140, 230),
                (false, Track::Cage) => egui::Color32::from_rgb(235, 130, 30),
            };
            let s = 6.0;
            painter.add(egui::Shape::convex_polygon(
                vec![
                    centre + egui::vec2(0.0, -s),
                    centre + egui::vec2(s, 0.0),
                    centre + egui::vec2(0.0, s),
                    centre + egui::vec2(-s, 0.0),
                ],
                color,
                egui::Stroke::new(1.0, egui::Color32::BLACK),
            ));
            if pointer.is_some_and(|p| p.distance(centre) <= 8.0) {
                hovered_key = Some((*track, i));
            }
        }
    }
    let playhead = to_x(app.timeline.time);
    painter.line_segment(
        [
            egui::pos2(playhead, rect.top()),
            egui::pos2(playhead, rect.bottom()),
        ],
        egui::Stroke::new(2.0, egui::Color32::from_rgb(220, 60, 60)),
    );
    // Interaction: click a key to select it, drag it to move it; elsewhere click / drag scrubs.
    if response.drag_started()
        && let Some((track, i)) = hovered_key
    {
        {
            app.timeline.selected = Some((track, i));
            let t = match track {
                Track::Skeleton => skeleton_times[i],
                Track::Cage => cage_times[i],
            };
            app.timeline.dragging = Some((track, i, t));
        }
    }
    if let Some(pos) = response.interact_pointer_pos() {
        let t = to_t(pos.x);
        if let Some(d) = &mut app.timeline.dragging {
            d.2 = (t * 100.0).round() / 100.0;
        } else if response.dragged() || response.clicked() {
            if response.clicked() && hovered_key.is_some() {
                app.timeline.selected = hovered_key;
            } else {
                app.scrub_to(t);
            }
        }
    }
    if response.drag_stopped()
        && let Some((track, index, time)) = app.timeline.dragging.take()
    {
        let old = match track {
            Track::Skeleton => skeleton_times.get(index),
            Track::Cage => cage_times.get(index),
        };
        if old.is_some_and(|&o| (o - time).abs() > 1e-9)
            && app.run_command(&Command::MoveKey { track, index, time })
            && let Some(doc) = &app.doc
        {
            app.timeline.selected = doc.keys.index_at(track, time).map(|i| (track, i));
        }
    }
}

impl StudioApp {
    pub fn toggle_play(&mut self) {
        let duration = self.doc.as_ref().map_or(0.0, |d| d.keys.duration());
        if self.doc.as_ref().is_none_or(|d| d.keys.is_empty()) {
            self.log_warning(
                "nothing to play: set keys first (K: skeleton key, Shift+K: cage key)",
            );
            return;
        }
        if !self.timeline.playing && self.timeline.time >= duration && !self.timeline.looping {
            self.timeline.time = 0.0;
        }
        self.timeline.playing = !self.timeline.playing;
    }
}
