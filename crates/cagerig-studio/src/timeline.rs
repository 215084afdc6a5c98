//! The timeline: a skeleton track and a cage track with their keys, play / pause / loop /
//! speed, scrubbing, and key selection, moving and deletion.

use crate::diagnostics::Diagnostics;
use crate::doc_commands::{run_command, sample_keys};
use crate::document::{Command, Document};
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

impl TimelineState {
    /// Moves the playhead and samples the keys there.
    pub fn scrub_to(&mut self, time: f64, doc: Option<&mut Document>, diag: &mut Diagnostics) {
        self.time = time.max(0.0);
        if let Some(doc) = doc {
            sample_keys(doc, self.time, diag);
        }
    }

    /// Keys the current pose or rest cage at the playhead.
    pub fn set_key(&mut self, track: Track, doc: Option<&mut Document>, diag: &mut Diagnostics) {
        let time = self.time;
        if let Some(doc) = doc
            && run_command(doc, &Command::SetKey { track, time }, diag)
        {
            self.selected = doc.keys.index_at(track, time).map(|i| (track, i));
        }
    }

    /// Deletes the selected key.
    pub fn delete_selected_key(&mut self, doc: Option<&mut Document>, diag: &mut Diagnostics) {
        if let Some((track, index)) = self.selected.take()
            && let Some(doc) = doc
        {
            run_command(doc, &Command::DeleteKey { track, index }, diag);
        }
    }

    /// Play / pause (with a warning when there are no keys to play).
    pub fn toggle_play(&mut self, doc: Option<&Document>, diag: &mut Diagnostics) {
        let duration = doc.map_or(0.0, |d| d.keys.duration());
        if doc.is_none_or(|d| d.keys.is_empty()) {
            diag.log
                .warning("nothing to play: set keys first (K: skeleton key, Shift+K: cage key)");
            return;
        }
        if !self.playing && self.time >= duration && !self.looping {
            self.time = 0.0;
        }
        self.playing = !self.playing;
    }

    /// Once per frame while playing: moves the playhead by the frame's time and samples the
    /// keys there (looping, or stopping at the end).
    pub fn advance(
        &mut self,
        ctx: &egui::Context,
        doc: Option<&mut Document>,
        diag: &mut Diagnostics,
    ) {
        if !self.playing {
            return;
        }
        let dt = f64::from(ctx.input(|i| i.stable_dt)).min(0.1);
        let Some(doc) = doc else { return };
        let duration = doc.keys.duration();
        let mut t = self.time + dt * self.speed;
        if t > duration {
            if self.looping && duration > 0.0 {
                t = t.rem_euclid(duration);
            } else {
                t = duration;
                self.playing = false;
            }
        }
        self.time = t;
        match doc.sample(t) {
            Ok(_) => diag.stats.sync_ms = doc.last_sync_ms,
            Err(e) => {
                self.playing = false;
                diag.log.error(format!("playback: {e}"));
            }
        }
        ctx.request_repaint();
    }
}

/// The bottom panel with the transport and the two tracks.
pub fn timeline_ui(
    ui: &mut egui::Ui,
    mut doc: Option<&mut Document>,
    timeline: &mut TimelineState,
    diag: &mut Diagnostics,
) {
    egui::Panel::bottom("timeline")
        .resizable(false)
        .show(ui, |ui| {
            transport_ui(ui, doc.as_deref_mut(), timeline, diag);
            if let Some(doc) = doc {
                tracks_ui(ui, doc, timeline, diag);
            }
        });
}

fn transport_ui(
    ui: &mut egui::Ui,
    mut doc: Option<&mut Document>,
    timeline: &mut TimelineState,
    diag: &mut Diagnostics,
) {
    ui.horizontal(|ui| {
        let play_label = if timeline.playing { "Pause" } else { "Play" };
        if ui.button(play_label).on_hover_text("Space").clicked() {
            timeline.toggle_play(doc.as_deref(), diag);
        }
        if ui.button("Rewind").on_hover_text("Back to 0 s").clicked() {
            timeline.scrub_to(0.0, doc.as_deref_mut(), diag);
        }
        ui.checkbox(&mut timeline.looping, "Loop");
        ui.label("Speed");
        ui.add(
            egui::DragValue::new(&mut timeline.speed)
                .range(0.05..=8.0)
                .speed(0.01)
                .suffix("×"),
        );
        ui.label("Time");
        let mut t = timeline.time;
        if ui
            .add(
                egui::DragValue::new(&mut t)
                    .range(0.0..=3600.0)
                    .speed(0.01)
                    .suffix(" s"),
            )
            .changed()
        {
            timeline.scrub_to(t, doc.as_deref_mut(), diag);
        }
        ui.separator();
        if ui
            .button("Key skeleton")
            .on_hover_text("K: key the current pose S'")
            .clicked()
        {
            timeline.set_key(Track::Skeleton, doc.as_deref_mut(), diag);
        }
        if ui
            .button("Key cage")
            .on_hover_text("Shift+K: key the rest cage C")
            .clicked()
        {
            timeline.set_key(Track::Cage, doc.as_deref_mut(), diag);
        }
        let has_selection = timeline.selected.is_some();
        if ui
            .add_enabled(has_selection, egui::Button::new("Delete key"))
            .clicked()
        {
            timeline.delete_selected_key(doc, diag);
        }
    });
}

fn tracks_ui(
    ui: &mut egui::Ui,
    doc: &mut Document,
    timeline: &mut TimelineState,
    diag: &mut Diagnostics,
) {
    let skeleton_times: Vec<f64> = doc.keys.skeleton.iter().map(|k| k.time).collect();
    let cage_times: Vec<f64> = doc.keys.cage.iter().map(|k| k.time).collect();
    let span = (doc.keys.duration().max(timeline.time) + 1.0).max(2.0);
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
            let dragged = timeline
                .dragging
                .filter(|&(dt, di, _)| dt == *track && di == i)
                .map(|(_, _, t)| t);
            let x = to_x(dragged.unwrap_or(kt));
            let centre = egui::pos2(x, y);
            let selected = timeline.selected == Some((*track, i));
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
    let playhead = to_x(timeline.time);
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
            timeline.selected = Some((track, i));
            let t = match track {
                Track::Skeleton => skeleton_times[i],
                Track::Cage => cage_times[i],
            };
            timeline.dragging = Some((track, i, t));
        }
    }
    if let Some(pos) = response.interact_pointer_pos() {
        let t = to_t(pos.x);
        if let Some(d) = &mut timeline.dragging {
            d.2 = (t * 100.0).round() / 100.0;
        } else if response.dragged() || response.clicked() {
            if response.clicked() && hovered_key.is_some() {
                timeline.selected = hovered_key;
            } else {
                timeline.scrub_to(t, Some(&mut *doc), diag);
            }
        }
    }
    if response.drag_stopped()
        && let Some((track, index, time)) = timeline.dragging.take()
    {
        let old = match track {
            Track::Skeleton => skeleton_times.get(index),
            Track::Cage => cage_times.get(index),
        };
        if old.is_some_and(|&o| (o - time).abs() > 1e-9)
            && run_command(doc, &Command::MoveKey { track, index, time }, diag)
        {
            timeline.selected = doc.keys.index_at(track, time).map(|i| (track, i));
        }
    }
}
