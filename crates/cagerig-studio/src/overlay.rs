//! What egui paints over a view's 3D picture: its title, the selection, the gizmo, the name of
//! the joint under the mouse, the box selection, and the out-of-sync warning of the locks.

use cagerig::session::RigSession;
use egui::{Color32, Pos2, Stroke};
use glam::{DVec2, DVec3};

use crate::document_skeleton::ShownSkeleton;
use crate::gizmo::{self, Axis};
use crate::picking::ViewProjection;
use crate::selection::Tool;
use crate::tools::Tools;
use crate::view_state::CURRENT;

const SELECTED: Color32 = Color32::from_rgb(255, 214, 0);

fn axis_color(axis: Axis) -> Color32 {
    match axis {
        Axis::X => Color32::from_rgb(225, 60, 60),
        Axis::Y => Color32::from_rgb(60, 180, 60),
        Axis::Z => Color32::from_rgb(60, 110, 235),
    }
}

fn to_screen(p: DVec2, rect: egui::Rect) -> Pos2 {
    Pos2::new(rect.left() + p.x as f32, rect.top() + p.y as f32)
}

/// Paints the overlays of view `view` (seen through `projection`) inside `rect`.
pub fn overlay_ui(
    painter: &egui::Painter,
    rect: egui::Rect,
    view: usize,
    projection: &ViewProjection,
    s: &RigSession,
    skeleton: &ShownSkeleton,
    tools: &Tools,
) {
    let current = view == CURRENT;
    let title = if current {
        "Current pose (M', S', C')"
    } else {
        "Rest pose (M, S, C)"
    };
    painter.text(
        rect.left_top() + egui::vec2(8.0, 6.0),
        egui::Align2::LEFT_TOP,
        title,
        egui::FontId::proportional(13.0),
        Color32::from_gray(40),
    );
    let locks = s.sync_locks();
    if !locks.none() {
        let mut text = Vec::new();
        if locks.skel_up {
            text.push("SkelUp locked: the rest skeleton does not follow the rest cage");
        }
        if locks.cage_up {
            text.push("CageUp locked: the current cage does not follow the pose");
        }
        painter.text(
            rect.left_top() + egui::vec2(8.0, 24.0),
            egui::Align2::LEFT_TOP,
            format!("Out of sync — {}", text.join("; ")),
            egui::FontId::proportional(12.0),
            Color32::from_rgb(200, 30, 30),
        );
    }
    // Selected cage vertices.
    let cage = if current {
        s.posed_cage()
    } else {
        s.rest_cage()
    };
    for &k in &tools.selection.cage {
        if let Some(p) = cage.get(k).and_then(|p| projection.project(*p)) {
            painter.circle(
                to_screen(p, rect),
                5.5,
                SELECTED,
                Stroke::new(1.5, Color32::BLACK),
            );
        }
    }
    // Selected and hovered joints.
    let joint = |j: usize| -> Option<(DVec2, &str)> {
        let p = projection.project(*skeleton.positions.get(j)?)?;
        Some((p, skeleton.names.get(j)?.as_str()))
    };
    if let Some(j) = tools.selection.joint
        && let Some((p, name)) = joint(j)
    {
        painter.circle_stroke(to_screen(p, rect), 9.0, Stroke::new(2.5, SELECTED));
        label(painter, to_screen(p, rect), name);
    }
    if let Some((v, j)) = tools.interaction.hovered_joint
        && v == view
        && tools.selection.joint != Some(j)
        && let Some((p, name)) = joint(j)
    {
        painter.circle_stroke(to_screen(p, rect), 8.0, Stroke::new(1.5, Color32::WHITE));
        label(painter, to_screen(p, rect), name);
    }
    // Gizmo.
    if let Some((pivot, arrows, rings)) = tools.gizmo_pivot(s, skeleton, view) {
        draw_gizmo(painter, rect, projection, pivot, arrows, rings, tools);
    }
    // Box selection.
    if let Some((v, start)) = tools.interaction.box_select
        && v == view
        && let Some(now) = painter.ctx().input(|i| i.pointer.hover_pos())
    {
        let r = egui::Rect::from_two_pos(to_screen(start, rect), now);
        painter.rect_stroke(
            r,
            0.0,
            Stroke::new(1.0, Color32::from_gray(30)),
            egui::StrokeKind::Inside,
        );
        painter.rect_filled(r, 0.0, Color32::from_rgba_unmultiplied(255, 214, 0, 30));
    }
    // Transform status.
    if let Some(t) = &tools.interaction.transform
        && t.view == view
    {
        painter.text(
            rect.left_bottom() + egui::vec2(8.0, -8.0),
            egui::Align2::LEFT_BOTTOM,
            t.describe(),
            egui::FontId::proportional(12.0),
            Color32::from_gray(20),
        );
    }
}

fn label(painter: &egui::Painter, at: Pos2, text: &str) {
    let galley = painter.layout_no_wrap(
        text.to_string(),
        egui::FontId::proportional(12.0),
        Color32::WHITE,
    );
    let pos = at + egui::vec2(10.0, -22.0);
    let bg = egui::Rect::from_min_size(pos, galley.size()).expand(3.0);
    painter.rect_filled(bg, 3.0, Color32::from_black_alpha(170));
    painter.galley(pos, galley, Color32::WHITE);
}

fn draw_gizmo(
    painter: &egui::Painter,
    rect: egui::Rect,
    projection: &ViewProjection,
    pivot: DVec3,
    arrows: bool,
    rings: bool,
    tools: &Tools,
) {
    let Some(centre) = projection.project(pivot) else {
        return;
    };
    let hovered = tools
        .interaction
        .hovered_view
        .and_then(|_| painter.ctx().input(|i| i.pointer.hover_pos()))
        .filter(|p| rect.contains(*p))
        .and_then(|p| {
            gizmo::hit_handle(
                projection,
                pivot,
                DVec2::new(f64::from(p.x - rect.left()), f64::from(p.y - rect.top())),
                arrows,
                rings,
            )
        });
    painter.circle_filled(to_screen(centre, rect), 3.5, Color32::WHITE);
    if rings {
        for axis in Axis::ALL {
            let poly: Vec<Pos2> = gizmo::ring_polyline(projection, pivot, axis, 64)
                .into_iter()
                .map(|p| to_screen(p, rect))
                .collect();
            let width = if hovered == Some(gizmo::Handle::Ring(axis)) {
                4.0
            } else {
                2.0
            };
            painter.add(egui::Shape::closed_line(
                poly,
                Stroke::new(width, axis_color(axis)),
            ));
        }
    }
    if arrows {
        // Plane handles, coloured by their normal axis (as in Blender).
        for axis in Axis::ALL {
            let Some(square) = gizmo::plane_square(projection, pivot, axis) else {
                continue;
            };
            let alpha = if hovered == Some(gizmo::Handle::Plane(axis)) {
                200
            } else {
                110
            };
            let [r, g, b, _] = axis_color(axis).to_array();
            painter.add(egui::Shape::convex_polygon(
                square.iter().map(|&p| to_screen(p, rect)).collect(),
                Color32::from_rgba_unmultiplied(r, g, b, alpha),
                Stroke::new(1.0, axis_color(axis)),
            ));
        }
        for axis in Axis::ALL {
            let Some((a, b)) = gizmo::arrow_segment(projection, pivot, axis) else {
                continue;
            };
            let width = if hovered == Some(gizmo::Handle::Arrow(axis)) {
                4.5
            } else {
                2.5
            };
            let color = axis_color(axis);
            let (a, b) = (to_screen(a, rect), to_screen(b, rect));
            painter.line_segment([a, b], Stroke::new(width, color));
            let square = tools.tool == Tool::Scale;
            if square {
                painter.rect_filled(
                    egui::Rect::from_center_size(b, egui::vec2(9.0, 9.0)),
                    0.0,
                    color,
                );
            } else {
                let dir = (b - a).normalized();
                let side = egui::vec2(-dir.y, dir.x);
                painter.add(egui::Shape::convex_polygon(
                    vec![b + dir * 10.0, b + side * 5.0, b - side * 5.0],
                    color,
                    Stroke::NONE,
                ));
            }
            painter.text(
                b + (b - a).normalized() * 16.0,
                egui::Align2::CENTER_CENTER,
                axis.name(),
                egui::FontId::proportional(11.0),
                color,
            );
        }
    }
}
