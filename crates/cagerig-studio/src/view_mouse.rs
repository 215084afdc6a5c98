//! What the mouse does in a view: orbit / pan / zoom, picking and box selection, gizmo
//! handles, and dragging selected elements (one transform per drag).

use cagerig_render::OrbitCamera;
use glam::DVec2;

use crate::diagnostics::Diagnostics;
use crate::doc_commands::run_command;
use crate::document::{Command, Document, SkeletonEdit};
use crate::gizmo::{self, Constraint, Handle};
use crate::joint_placement::joint_in_body;
use crate::selection::{Picked, Tool};
use crate::tools::Tools;
use crate::transform::{TransformOp, TransformStart};
use crate::view_picking::ViewPicker;
use crate::view_state::{CURRENT, REST, ViewState};

/// A screen position in view pixels of the view at `rect`.
pub fn to_view(pos: egui::Pos2, rect: egui::Rect) -> DVec2 {
    DVec2::new(
        f64::from(pos.x - rect.left()),
        f64::from(pos.y - rect.top()),
    )
}

/// Orbit (middle drag, Alt+left drag), pan (Shift+middle, right drag when no transform
/// runs, Alt+Shift+left) and zoom (wheel, pinch) of a view's camera.
pub fn navigate(
    ui: &egui::Ui,
    response: &egui::Response,
    camera: &mut OrbitCamera,
    transform_running: bool,
) {
    let (modifiers, scroll, zoom) =
        ui.input(|i| (i.modifiers, i.smooth_scroll_delta, i.zoom_delta()));
    let delta = response.drag_delta();
    let height = f64::from(response.rect.height().max(1.0));
    let orbit = response.dragged_by(egui::PointerButton::Middle) && !modifiers.shift
        || response.dragged_by(egui::PointerButton::Primary) && modifiers.alt && !modifiers.shift;
    let pan = response.dragged_by(egui::PointerButton::Middle) && modifiers.shift
        || response.dragged_by(egui::PointerButton::Secondary) && !transform_running
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

/// Clicks and drags in view `view` (whose area is `response.rect`): the hovered joint, a
/// modal transform following the mouse, drags on the gizmo, on the selection or for a box,
/// and click selection.
pub fn handle_mouse(
    ui: &egui::Ui,
    response: &egui::Response,
    view: usize,
    doc: &mut Document,
    views: &ViewState,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    let rect = response.rect;
    let modifiers = ui.input(|i| i.modifiers);
    let hover = response.hover_pos().map(|p| to_view(p, rect));
    if tools
        .interaction
        .transform
        .as_ref()
        .is_some_and(|t| t.view == view)
        && hover.is_some()
    {
        tools.interaction.last_mouse = hover;
    }
    // Hovered joint name (joints only: cheap, no occlusion test, fine every frame).
    if let Some(m) = hover {
        let picked = ViewPicker::new(doc, views, view)
            .pick_joint(m)
            .map(Picked::Joint);
        match picked {
            Some(Picked::Joint(j)) if tools.interaction.transform.is_none() => {
                tools.interaction.hovered_joint = Some((view, j));
            }
            _ => {
                if tools
                    .interaction
                    .hovered_joint
                    .is_some_and(|(v, _)| v == view)
                {
                    tools.interaction.hovered_joint = None;
                }
            }
        }
    }
    // A modal transform follows the mouse; click confirms, right click cancels.
    if let Some(t) = &tools.interaction.transform
        && t.view == view
        && t.modal
    {
        if response.clicked_by(egui::PointerButton::Primary) {
            tools.confirm_transform(Some(doc));
        } else if response.clicked_by(egui::PointerButton::Secondary) {
            tools.cancel_transform(Some(doc), &mut diag.log);
        } else if let Some(m) = hover
            && t.typed.is_empty()
        {
            tools.update_transform(Some(doc), views, m, diag);
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
        start_drag(view, origin, modifiers, doc, views, tools, diag);
    }
    if response.dragged_by(primary)
        && let Some(m) = response.interact_pointer_pos().map(|p| to_view(p, rect))
        && tools
            .interaction
            .transform
            .as_ref()
            .is_some_and(|t| t.view == view)
    {
        tools.update_transform(Some(doc), views, m, diag);
    }
    if response.drag_stopped_by(primary) {
        if tools
            .interaction
            .transform
            .as_ref()
            .is_some_and(|t| t.view == view && !t.modal)
        {
            tools.confirm_transform(Some(doc));
        }
        if let Some((v, start)) = tools.interaction.box_select.take()
            && v == view
            && let Some(end) = response.interact_pointer_pos().map(|p| to_view(p, rect))
        {
            let inside = ViewPicker::new(doc, views, view).cage_in_box(start, end);
            tools.selection.box_select(inside, modifiers);
        }
    }
    if response.clicked_by(primary)
        && let Some(m) = response.interact_pointer_pos().map(|p| to_view(p, rect))
    {
        let picked = ViewPicker::new(doc, views, view).pick(m);
        if tools.add_joints && view == REST && !matches!(picked, Some(Picked::Joint(_))) {
            add_joint_at(doc, views, m, tools, diag);
        } else {
            tools.selection.click(picked, modifiers);
        }
    }
}

/// Adds a joint in the middle of the body under `mouse` (rest view), below the selected
/// joint, and selects it: successive clicks build a chain.
fn add_joint_at(
    doc: &mut Document,
    views: &ViewState,
    mouse: DVec2,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    let (origin, dir) = views.projection(REST).ray(mouse);
    let s = &doc.session;
    let Some(position) = joint_in_body(origin, dir, s.rest_mesh(), s.mesh_triangles()) else {
        diag.log
            .warning("no joint added: click on the mesh (the joint goes inside the body)");
        return;
    };
    let count = doc.shown_skeleton(true).positions.len();
    let parent = tools.selection.joint.filter(|&j| j < count);
    let mirror = doc.mirror_x.then(|| doc.mirror());
    let command = Command::EditSkeleton(SkeletonEdit::Add {
        position,
        parent,
        mirror,
    });
    if run_command(doc, &command, diag) {
        // The new joint is pushed first, its mirror twin (if any) after it.
        tools.selection.cage.clear();
        tools.selection.joint = Some(count);
        tools.selection.joint_is_active = true;
    }
}

/// A primary drag starts on a gizmo handle, on a selected element, or as a box selection.
fn start_drag(
    view: usize,
    origin: DVec2,
    modifiers: egui::Modifiers,
    doc: &mut Document,
    views: &ViewState,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    let projection = views.projection(view);
    let start = |op, constraint, trackball| TransformStart {
        view,
        op,
        constraint,
        mouse: origin,
        modal: false,
        trackball,
    };
    let skeleton = doc.shown_skeleton(view == REST);
    if let Some((pivot, arrows, rings)) = tools.gizmo_pivot(&doc.session, &skeleton, view) {
        let handle = gizmo::hit_handle(
            &projection,
            pivot,
            origin,
            arrows,
            rings || tools.selection.joint_active(),
        );
        let op_and_constraint = match handle {
            Some(Handle::Arrow(a)) if tools.tool == Tool::Scale => {
                Some((TransformOp::Scale, Constraint::Axis(a)))
            }
            Some(Handle::Arrow(a)) => Some((TransformOp::Grab, Constraint::Axis(a))),
            Some(Handle::Plane(a)) if tools.tool == Tool::Scale => {
                Some((TransformOp::Scale, Constraint::Plane(a)))
            }
            Some(Handle::Plane(a)) => Some((TransformOp::Grab, Constraint::Plane(a))),
            Some(Handle::Ring(a)) => Some((TransformOp::Rotate, Constraint::Axis(a))),
            None => None,
        };
        if let Some((op, constraint)) = op_and_constraint
            && tools.begin_transform(Some(&mut *doc), start(op, constraint, false), &mut diag.log)
        {
            return;
        }
    }
    match ViewPicker::new(doc, views, view).pick(origin) {
        Some(Picked::CageVertex(k)) if tools.selection.cage.contains(&k) && !modifiers.shift => {
            tools.selection.joint_is_active = false;
            let op = match tools.tool {
                Tool::Move => TransformOp::Grab,
                Tool::Rotate => TransformOp::Rotate,
                Tool::Scale => TransformOp::Scale,
            };
            tools.begin_transform(Some(doc), start(op, Constraint::Free, false), &mut diag.log);
        }
        Some(Picked::Joint(j)) if view == CURRENT && !modifiers.shift => {
            tools.selection.joint = Some(j);
            tools.selection.joint_is_active = true;
            tools.begin_transform(
                Some(doc),
                start(TransformOp::Rotate, Constraint::Free, true),
                &mut diag.log,
            );
        }
        Some(Picked::Joint(j)) if view == REST && !modifiers.shift => {
            tools.selection.joint = Some(j);
            tools.selection.joint_is_active = true;
            tools.begin_transform(
                Some(doc),
                start(TransformOp::Grab, Constraint::Free, false),
                &mut diag.log,
            );
        }
        _ => tools.interaction.box_select = Some((view, origin)),
    }
}
