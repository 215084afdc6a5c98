//! The two 3D views and what the mouse and keys do in them: orbit / pan / zoom, picking and
//! box selection, gizmo handles, dragging selected elements, and the G / R / S keys.

use egui_wgpu::RenderState;
use glam::{DVec2, DVec3};

use crate::app::{CURRENT, Layout, REST, StudioApp, Tool};
use crate::gizmo::{self, Axis, Constraint, Handle};
use crate::picking::{Occluder, ViewProjection, pick_box, pick_nearest};
use crate::transform::{TransformOp, TransformTarget};

/// Pixels within which a click picks a cage vertex or a joint.
pub const PICK_PIXELS: f64 = 12.0;

/// Mouse state shared by the views.
#[derive(Debug, Clone)]
pub struct Interaction {
    pub transform: Option<crate::transform::Transform>,
    /// Box selection: the view and the corner where it started (view pixels).
    pub box_select: Option<(usize, DVec2)>,
    /// The view under the mouse.
    pub hovered_view: Option<usize>,
    /// A joint under the mouse: (view, joint).
    pub hovered_joint: Option<(usize, usize)>,
    /// Last mouse position over the view of the transform (view pixels).
    pub last_mouse: Option<DVec2>,
    /// Screen rectangles of the views as last laid out.
    pub view_rects: [egui::Rect; 2],
}

impl Default for Interaction {
    fn default() -> Self {
        Self {
            transform: None,
            box_select: None,
            hovered_view: None,
            hovered_joint: None,
            last_mouse: None,
            view_rects: [egui::Rect::NOTHING; 2],
        }
    }
}

/// What a click in a view hits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Picked {
    CageVertex(usize),
    Joint(usize),
}

impl StudioApp {
    /// The skin of `view`'s pose as an occluder of picking (`None` when the skin is hidden).
    fn skin_occluder(&self, view: usize) -> Option<Occluder<'_>> {
        let s = &self.doc.as_ref()?.session;
        self.layers.mesh.then(|| Occluder {
            positions: if view == CURRENT {
                s.posed_mesh()
            } else {
                s.rest_mesh()
            },
            triangles: s.mesh_triangles(),
        })
    }

    /// The element under `mouse` (view pixels) in view `view`: the nearest on screen of the
    /// visible joints (drawn on top) and the cage vertices not hidden by the skin.
    pub fn pick(&self, view: usize, mouse: DVec2) -> Option<Picked> {
        let doc = self.doc.as_ref()?;
        let s = &doc.session;
        let projection = self.views[view].projection();
        let current = view == CURRENT;
        let occluder = self.skin_occluder(view);
        let joints: Vec<DVec3> = if current {
            s.posed_joints().collect()
        } else {
            s.rest_joints().collect()
        };
        let cage = if current {
            s.posed_cage()
        } else {
            s.rest_cage()
        };
        let screen_distance = |p: DVec3| {
            projection
                .project(p)
                .map_or(f64::INFINITY, |q| q.distance(mouse))
        };
        let joint = self
            .layers
            .skeleton
            .then(|| pick_nearest(&projection, &joints, mouse, PICK_PIXELS, None))
            .flatten();
        let vertex = self
            .layers
            .cage
            .then(|| pick_nearest(&projection, cage, mouse, PICK_PIXELS, occluder))
            .flatten();
        match (joint, vertex) {
            (Some(j), Some(k)) if screen_distance(cage[k]) < screen_distance(joints[j]) => {
                Some(Picked::CageVertex(k))
            }
            (Some(j), _) => Some(Picked::Joint(j)),
            (None, Some(k)) => Some(Picked::CageVertex(k)),
            (None, None) => None,
        }
    }

    /// The joint under `mouse` in view `view` (joints are drawn on top: no occlusion).
    pub fn pick_joint(&self, view: usize, mouse: DVec2) -> Option<usize> {
        let doc = self.doc.as_ref()?;
        if !self.layers.skeleton {
            return None;
        }
        let s = &doc.session;
        let joints: Vec<DVec3> = if view == CURRENT {
            s.posed_joints().collect()
        } else {
            s.rest_joints().collect()
        };
        pick_nearest(
            &self.views[view].projection(),
            &joints,
            mouse,
            PICK_PIXELS,
            None,
        )
    }

    /// Applies a click on `picked` (shift adds / toggles, ctrl removes, else replaces).
    pub fn click_select(&mut self, picked: Option<Picked>, modifiers: egui::Modifiers) {
        let sel = &mut self.selection;
        match picked {
            Some(Picked::CageVertex(k)) => {
                if modifiers.command {
                    sel.cage.remove(&k);
                } else if modifiers.shift {
                    if !sel.cage.remove(&k) {
                        sel.cage.insert(k);
                    }
                } else {
                    sel.cage.clear();
                    sel.cage.insert(k);
                }
                sel.joint_is_active = false;
            }
            Some(Picked::Joint(j)) => {
                if modifiers.command {
                    if sel.joint == Some(j) {
                        sel.joint = None;
                    }
                } else {
                    sel.joint = Some(j);
                    sel.joint_is_active = true;
                    if !modifiers.shift {
                        sel.cage.clear();
                    }
                }
            }
            None => {
                if !modifiers.shift && !modifiers.command {
                    sel.cage.clear();
                    sel.joint = None;
                }
            }
        }
    }

    /// Box selection of cage vertices between two corners (view pixels).
    pub fn box_select(&mut self, view: usize, a: DVec2, b: DVec2, modifiers: egui::Modifiers) {
        let Some(doc) = &self.doc else { return };
        let s = &doc.session;
        let current = view == CURRENT;
        let projection = self.views[view].projection();
        let occluder = self.skin_occluder(view);
        let cage = if current {
            s.posed_cage()
        } else {
            s.rest_cage()
        };
        let inside = pick_box(&projection, cage, a, b, occluder);
        let sel = &mut self.selection;
        if modifiers.command {
            for k in inside {
                sel.cage.remove(&k);
            }
        } else {
            if !modifiers.shift {
                sel.cage.clear();
            }
            sel.cage.extend(inside);
        }
        sel.joint_is_active = false;
    }

    /// Where the gizmo of the active selection sits in `view`, and which handles it shows.
    pub fn gizmo_pivot(&self, view: usize) -> Option<(DVec3, bool, bool)> {
        let doc = self.doc.as_ref()?;
        let s = &doc.session;
        if let Some(t) = &self.interaction.transform {
            return (t.view == view).then_some((t.pivot, false, false));
        }
        if self.selection.joint_active() {
            let j = self.selection.joint?;
            return (view == CURRENT)
                .then(|| (s.posed_world_from_joint()[j].translation, false, true));
        }
        if self.selection.cage.is_empty() {
            return None;
        }
        let cage = if view == CURRENT {
            s.posed_cage()
        } else {
            s.rest_cage()
        };
        let centre = self.selection.cage.iter().map(|&k| cage[k]).sum::<DVec3>()
            / self.selection.cage.len() as f64;
        let (arrows, rings) = match self.tool {
            Tool::Move | Tool::Scale => (true, false),
            Tool::Rotate => (false, true),
        };
        Some((centre, arrows, rings))
    }
}

fn to_view(pos: egui::Pos2, rect: egui::Rect) -> DVec2 {
    DVec2::new(
        f64::from(pos.x - rect.left()),
        f64::from(pos.y - rect.top()),
    )
}

/// Lays out and draws the views, and handles their input.
pub fn views_ui(app: &mut StudioApp, ui: &mut egui::Ui, render_state: Option<&RenderState>) {
    egui::CentralPanel::default().show(ui, |ui| {
        if app.doc.is_none() {
            ui.centered_and_justified(|ui| {
                ui.label("No rig open: File > Open, or drop a file here.");
            });
            return;
        }
        let visible: Vec<usize> = match app.layout {
            Layout::Split => vec![CURRENT, REST],
            Layout::CurrentOnly => vec![CURRENT],
            Layout::RestOnly => vec![REST],
        };
        let available = ui.available_rect_before_wrap();
        let gap = 4.0;
        let n = visible.len() as f32;
        let width = (available.width() - gap * (n - 1.0)) / n;
        app.interaction.hovered_view = None;
        for (i, &view) in visible.iter().enumerate() {
            let rect = egui::Rect::from_min_size(
                available.min + egui::vec2(i as f32 * (width + gap), 0.0),
                egui::vec2(width, available.height()),
            );
            view_ui(app, ui, rect, view, render_state);
        }
    });
}

fn view_ui(
    app: &mut StudioApp,
    ui: &mut egui::Ui,
    rect: egui::Rect,
    view: usize,
    render_state: Option<&RenderState>,
) {
    let id = ui.scope_id().with(("view", view));
    let response = ui.interact(rect, id, egui::Sense::click_and_drag());
    app.views[view].size_points = rect.size();
    app.interaction.view_rects[view] = rect;
    if !app.views[view].framed
        && let Some(doc) = &app.doc
    {
        // A gentle three-quarter view: slightly from the right and above.
        let v = &mut app.views[view];
        v.camera.yaw = 20f64.to_radians();
        v.camera.pitch = 15f64.to_radians();
        v.frame_all(&doc.session, None);
    }
    if response.hovered() || response.dragged() {
        app.interaction.hovered_view = Some(view);
    }
    navigate(app, ui, &response, view);
    handle_mouse(app, ui, &response, rect, view);
    // Draw.
    let ppp = ui.ctx().pixels_per_point();
    let size = (
        (rect.width() * ppp).round().max(1.0) as u32,
        (rect.height() * ppp).round().max(1.0) as u32,
    );
    let color_by = app.color_by();
    let layers = app.layers;
    let texture = match (render_state, app.renderer().cloned(), &app.doc) {
        (Some(rs), Some(renderer), Some(doc)) => {
            let result = app.views[view].prepare(
                rs,
                &renderer,
                &doc.session,
                if view == CURRENT {
                    doc.revision
                } else {
                    doc.rest_revision
                },
                layers,
                color_by,
                size,
            );
            app.stats.upload_ms += app.views[view].last_upload_ms;
            app.stats.render_ms += app.views[view].last_render_ms;
            match result {
                Ok(t) => Some(t),
                Err(e) => {
                    let message = e.to_string();
                    if app.render_error.as_deref() != Some(message.as_str()) {
                        app.log_error(format!("drawing the view: {message}"));
                        app.render_error = Some(message);
                    }
                    None
                }
            }
        }
        _ => None,
    };
    let painter = ui.painter_at(rect);
    match texture {
        Some(t) => painter.image(
            t,
            rect,
            egui::Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0)),
            egui::Color32::WHITE,
        ),
        None => painter.rect_filled(rect, 0.0, egui::Color32::from_gray(200)),
    };
    crate::overlay::overlay_ui(app, &painter, rect, view);
}

fn navigate(app: &mut StudioApp, ui: &egui::Ui, response: &egui::Response, view: usize) {
    let camera = &mut app.views[view].camera;
    let (modifiers, scroll, zoom) =
        ui.input(|i| (i.modifiers, i.smooth_scroll_delta, i.zoom_delta()));
    let delta = response.drag_delta();
    let height = f64::from(response.rect.height().max(1.0));
    let orbit = response.dragged_by(egui::PointerButton::Middle) && !modifiers.shift
        || response.dragged_by(egui::PointerButton::Primary) && modifiers.alt && !modifiers.shift;
    let pan = response.dragged_by(egui::PointerButton::Middle) && modifiers.shift
        || response.dragged_by(egui::PointerButton::Secondary)
            && app.interaction.transform.is_none()
        || response.dragged_by(egui::PointerButton::Primary) && modifiers.alt && modifiers.shift;
    if orbit {
        camera.orbit(-f64::from(delta.x) * 0.008, f64::from(delta.y) * 0.008);
    } else if pan {
        camera.pan(f64::from(delta.x) / height, f64::from(delta.y) / height);
    }
    if response.hovered() {
        if scroll.y != 0.0 {
            camera.zoom((-f64::from(scroll.y) * 0.002).exp());
        }
        if scroll.x != 0.0 {
            camera.orbit(-f64::from(scroll.x) * 0.005, 0.0);
        }
        if zoom != 1.0 {
            camera.zoom(1.0 / f64::from(zoom));
        }
    }
}

fn handle_mouse(
    app: &mut StudioApp,
    ui: &egui::Ui,
    response: &egui::Response,
    rect: egui::Rect,
    view: usize,
) {
    let modifiers = ui.input(|i| i.modifiers);
    let hover = response.hover_pos().map(|p| to_view(p, rect));
    if app
        .interaction
        .transform
        .as_ref()
        .is_some_and(|t| t.view == view)
        && hover.is_some()
    {
        app.interaction.last_mouse = hover;
    }
    // Hovered joint name (joints only: cheap, no occlusion test, fine every frame).
    if let Some(m) = hover {
        match app.pick_joint(view, m).map(Picked::Joint) {
            Some(Picked::Joint(j)) if app.interaction.transform.is_none() => {
                app.interaction.hovered_joint = Some((view, j));
            }
            _ => {
                if app
                    .interaction
                    .hovered_joint
                    .is_some_and(|(v, _)| v == view)
                {
                    app.interaction.hovered_joint = None;
                }
            }
        }
    }
    // A modal transform follows the mouse; click confirms, right click cancels.
    if let Some(t) = &app.interaction.transform
        && t.view == view
        && t.modal
    {
        if response.clicked_by(egui::PointerButton::Primary) {
            app.confirm_transform();
        } else if response.clicked_by(egui::PointerButton::Secondary) {
            app.cancel_transform();
        } else if let Some(m) = hover
            && t.typed.is_empty()
        {
            app.update_transform(m);
        }
        return;
    }
    if modifiers.alt {
        return;
    }
    let primary = egui::PointerButton::Primary;
    if response.drag_started_by(primary)
        && let Some(press) = response.interact_pointer_pos().map(|p| to_view(p, rect))
    {
        // Where the press started (the drag is reported a few pixels later).
        let origin = ui
            .input(|i| i.pointer.press_origin())
            .map_or(press, |p| to_view(p, rect));
        start_drag(app, view, origin, modifiers);
    }
    if response.dragged_by(primary)
        && let Some(m) = response.interact_pointer_pos().map(|p| to_view(p, rect))
        && app
            .interaction
            .transform
            .as_ref()
            .is_some_and(|t| t.view == view)
    {
        app.update_transform(m);
    }
    if response.drag_stopped_by(primary) {
        if app
            .interaction
            .transform
            .as_ref()
            .is_some_and(|t| t.view == view && !t.modal)
        {
            app.confirm_transform();
        }
        if let Some((v, start)) = app.interaction.box_select.take()
            && v == view
            && let Some(end) = response.interact_pointer_pos().map(|p| to_view(p, rect))
        {
            app.box_select(view, start, end, modifiers);
        }
    }
    if response.clicked_by(primary)
        && let Some(m) = response.interact_pointer_pos().map(|p| to_view(p, rect))
    {
        let picked = app.pick(view, m);
        app.click_select(picked, modifiers);
    }
}

/// A primary drag starts on a gizmo handle, on a selected element, or as a box selection.
fn start_drag(app: &mut StudioApp, view: usize, origin: DVec2, modifiers: egui::Modifiers) {
    let projection: ViewProjection = app.views[view].projection();
    if let Some((pivot, arrows, rings)) = app.gizmo_pivot(view) {
        let handle = gizmo::hit_handle(
            &projection,
            pivot,
            origin,
            arrows,
            rings || app.selection.joint_active(),
        );
        let op_and_constraint = match handle {
            Some(Handle::Arrow(a)) if app.tool == Tool::Scale => {
                Some((TransformOp::Scale, Constraint::Axis(a)))
            }
            Some(Handle::Arrow(a)) => Some((TransformOp::Grab, Constraint::Axis(a))),
            Some(Handle::Plane(a)) if app.tool == Tool::Scale => {
                Some((TransformOp::Scale, Constraint::Plane(a)))
            }
            Some(Handle::Plane(a)) => Some((TransformOp::Grab, Constraint::Plane(a))),
            Some(Handle::Ring(a)) => Some((TransformOp::Rotate, Constraint::Axis(a))),
            None => None,
        };
        if let Some((op, constraint)) = op_and_constraint
            && app.begin_transform(view, op, constraint, origin, false, false)
        {
            return;
        }
    }
    match app.pick(view, origin) {
        Some(Picked::CageVertex(k)) if app.selection.cage.contains(&k) && !modifiers.shift => {
            app.selection.joint_is_active = false;
            let op = match app.tool {
                Tool::Move => TransformOp::Grab,
                Tool::Rotate => TransformOp::Rotate,
                Tool::Scale => TransformOp::Scale,
            };
            app.begin_transform(view, op, Constraint::Free, origin, false, false);
        }
        Some(Picked::Joint(j)) if view == CURRENT && !modifiers.shift => {
            app.selection.joint = Some(j);
            app.selection.joint_is_active = true;
            app.begin_transform(
                view,
                TransformOp::Rotate,
                Constraint::Free,
                origin,
                false,
                true,
            );
        }
        _ => app.interaction.box_select = Some((view, origin)),
    }
}

/// Keys of the hovered view: G / R / S start a modal transform; during one, X / Y / Z
/// constrain, digits type a value, Enter confirms and Esc cancels; F frames the rig.
pub fn view_keys(app: &mut StudioApp, ctx: &egui::Context) {
    let events: Vec<egui::Event> = ctx.input(|i| i.events.clone());
    let hovered = app.interaction.hovered_view;
    let pointer = ctx.input(|i| i.pointer.hover_pos());
    for event in events {
        match event {
            egui::Event::Key {
                key,
                pressed: true,
                modifiers,
                ..
            } => {
                if let Some(t) = &mut app.interaction.transform {
                    if !t.modal && !matches!(key, egui::Key::Escape) {
                        continue;
                    }
                    let axis = match key {
                        egui::Key::X => Some(Axis::X),
                        egui::Key::Y => Some(Axis::Y),
                        egui::Key::Z => Some(Axis::Z),
                        _ => None,
                    };
                    if let Some(a) = axis {
                        t.toggle_axis(a, modifiers.shift);
                        reapply(app);
                    } else if key == egui::Key::Backspace {
                        t.typed.pop();
                        reapply(app);
                    } else if key == egui::Key::Minus {
                        t.typed = match t.typed.strip_prefix('-') {
                            Some(rest) => rest.to_string(),
                            None => format!("-{}", t.typed),
                        };
                        reapply(app);
                    } else if key == egui::Key::Enter {
                        app.confirm_transform();
                    } else if key == egui::Key::Escape {
                        app.cancel_transform();
                    }
                    continue;
                }
                if modifiers.command || modifiers.alt {
                    continue;
                }
                let Some(view) = hovered else { continue };
                let op = match key {
                    egui::Key::G => Some(TransformOp::Grab),
                    egui::Key::R => Some(TransformOp::Rotate),
                    egui::Key::S => Some(TransformOp::Scale),
                    _ => None,
                };
                if let (Some(op), Some(p)) = (op, pointer) {
                    let rect_min = app.interaction.view_rects[view].min;
                    let mouse =
                        DVec2::new(f64::from(p.x - rect_min.x), f64::from(p.y - rect_min.y));
                    app.interaction.last_mouse = Some(mouse);
                    app.begin_transform(view, op, Constraint::Free, mouse, true, false);
                } else if key == egui::Key::F
                    && let Some(doc) = &app.doc
                {
                    app.views[view].frame_all(&doc.session, None);
                }
            }
            egui::Event::Text(text) => {
                if let Some(t) = &mut app.interaction.transform
                    && t.modal
                {
                    let digits: String = text
                        .chars()
                        .filter(|c| c.is_ascii_digit() || *c == '.')
                        .collect();
                    if !digits.is_empty() {
                        t.typed.push_str(&digits);
                        reapply(app);
                    }
                }
            }
            _ => {}
        }
    }
}

/// Re-applies a modal transform after a constraint or typed value changed.
fn reapply(app: &mut StudioApp) {
    let Some(t) = &app.interaction.transform else {
        return;
    };
    let mouse = app.interaction.last_mouse.unwrap_or(t.start_mouse);
    app.update_transform(mouse);
}

/// Whether a transform target is a joint (for overlays).
pub fn is_joint_transform(target: &TransformTarget) -> bool {
    matches!(target, TransformTarget::Joint { .. })
}
