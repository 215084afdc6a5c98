//! Keys of the view under the mouse: G / R / S start a modal transform; during one, X / Y / Z
//! constrain, digits type a value, Enter confirms and Esc cancels; F frames the rig.

use glam::DVec2;

use crate::diagnostics::Diagnostics;
use crate::document::Document;
use crate::gizmo::{Axis, Constraint};
use crate::tools::Tools;
use crate::transform::{TransformOp, TransformStart};
use crate::view_state::ViewState;

/// Handles this frame's key and text events for the hovered view and a modal transform.
pub fn view_keys(
    ctx: &egui::Context,
    mut doc: Option<&mut Document>,
    views: &mut ViewState,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    let events: Vec<egui::Event> = ctx.input(|i| i.events.clone());
    let hovered = tools.interaction.hovered_view;
    let pointer = ctx.input(|i| i.pointer.hover_pos());
    for event in events {
        match event {
            egui::Event::Key {
                key,
                pressed: true,
                modifiers,
                ..
            } => {
                if let Some(t) = &mut tools.interaction.transform {
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
                        reapply(doc.as_deref_mut(), views, tools, diag);
                    } else if key == egui::Key::Backspace {
                        t.typed.pop();
                        reapply(doc.as_deref_mut(), views, tools, diag);
                    } else if key == egui::Key::Minus {
                        t.typed = match t.typed.strip_prefix('-') {
                            Some(rest) => rest.to_string(),
                            None => format!("-{}", t.typed),
                        };
                        reapply(doc.as_deref_mut(), views, tools, diag);
                    } else if key == egui::Key::Enter {
                        tools.confirm_transform(doc.as_deref_mut());
                    } else if key == egui::Key::Escape {
                        tools.cancel_transform(doc.as_deref_mut(), &mut diag.log);
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
                    let rect_min = tools.interaction.view_rects[view].min;
                    let mouse =
                        DVec2::new(f64::from(p.x - rect_min.x), f64::from(p.y - rect_min.y));
                    tools.interaction.last_mouse = Some(mouse);
                    let start = TransformStart {
                        view,
                        op,
                        constraint: Constraint::Free,
                        mouse,
                        modal: true,
                        trackball: false,
                    };
                    tools.begin_transform(doc.as_deref_mut(), start, &mut diag.log);
                } else if key == egui::Key::F
                    && let Some(doc) = doc.as_deref()
                {
                    views.views[view].frame_all(&doc.session, None);
                }
            }
            egui::Event::Text(text) => {
                if let Some(t) = &mut tools.interaction.transform
                    && t.modal
                {
                    let digits: String = text
                        .chars()
                        .filter(|c| c.is_ascii_digit() || *c == '.')
                        .collect();
                    if !digits.is_empty() {
                        t.typed.push_str(&digits);
                        reapply(doc.as_deref_mut(), views, tools, diag);
                    }
                }
            }
            _ => {}
        }
    }
}

/// Re-applies a modal transform after a constraint or typed value changed.
fn reapply(
    doc: Option<&mut Document>,
    views: &ViewState,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    let Some(t) = &tools.interaction.transform else {
        return;
    };
    let mouse = tools.interaction.last_mouse.unwrap_or(t.start_mouse);
    tools.update_transform(doc, views, mouse, diag);
}
