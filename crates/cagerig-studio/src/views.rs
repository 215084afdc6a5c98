//! The central panel: the two 3D views side by side (or one of them), each framed on the rig
//! when first shown, drawn by `cagerig-render`, with egui's overlays on top and the mouse
//! handled in `view_mouse`.

use std::sync::Arc;

use cagerig_render::Renderer;
use egui_wgpu::RenderState;

use crate::diagnostics::Diagnostics;
use crate::document::Document;
use crate::tools::Tools;
use crate::view_mouse::{handle_mouse, navigate};
use crate::view_state::{CURRENT, REST, ViewState};

/// What draws the views: eframe's wgpu state and the rig renderer.
#[derive(Clone, Copy)]
pub struct Gpu<'a> {
    pub render_state: &'a RenderState,
    pub renderer: &'a Arc<Renderer>,
}

/// Lays out and draws the views, and handles their input.
pub fn views_ui(
    ui: &mut egui::Ui,
    gpu: Option<Gpu<'_>>,
    doc: Option<&mut Document>,
    views: &mut ViewState,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    egui::CentralPanel::default().show(ui, |ui| {
        let Some(doc) = doc else {
            ui.centered_and_justified(|ui| {
                ui.label("No rig open: File > Open, or drop a file here.");
            });
            return;
        };
        let visible = views.visible();
        let available = ui.available_rect_before_wrap();
        let gap = 4.0;
        let n = visible.len() as f32;
        let width = (available.width() - gap * (n - 1.0)) / n;
        tools.interaction.hovered_view = None;
        for (i, &view) in visible.iter().enumerate() {
            let rect = egui::Rect::from_min_size(
                available.min + egui::vec2(i as f32 * (width + gap), 0.0),
                egui::vec2(width, available.height()),
            );
            view_ui(ui, rect, view, gpu, doc, views, tools, diag);
        }
    });
}

#[expect(clippy::too_many_arguments)]
fn view_ui(
    ui: &mut egui::Ui,
    rect: egui::Rect,
    view: usize,
    gpu: Option<Gpu<'_>>,
    doc: &mut Document,
    views: &mut ViewState,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    let id = ui.scope_id().with(("view", view));
    let response = ui.interact(rect, id, egui::Sense::click_and_drag());
    views.views[view].size_points = rect.size();
    tools.interaction.view_rects[view] = rect;
    if !views.views[view].framed {
        // A gentle three-quarter view: slightly from the right and above.
        let v = &mut views.views[view];
        v.camera.yaw = 20f64.to_radians();
        v.camera.pitch = 15f64.to_radians();
        v.frame_all(&doc.session, None);
    }
    if response.hovered() || response.dragged() {
        tools.interaction.hovered_view = Some(view);
    }
    let transform_running = tools.interaction.transform.is_some();
    navigate(
        ui,
        &response,
        &mut views.views[view].camera,
        transform_running,
    );
    handle_mouse(ui, &response, view, doc, views, tools, diag);
    // Draw.
    let ppp = ui.ctx().pixels_per_point();
    let size = (
        (rect.width() * ppp).round().max(1.0) as u32,
        (rect.height() * ppp).round().max(1.0) as u32,
    );
    let color_by = views.color_by(&tools.selection);
    let layers = views.layers;
    let skeleton = doc.shown_skeleton(view == REST);
    let texture = match gpu {
        Some(gpu) => {
            let v = &mut views.views[view];
            let result = v.prepare(
                gpu.render_state,
                gpu.renderer,
                &doc.session,
                if view == CURRENT {
                    doc.revision
                } else {
                    doc.rest_revision
                },
                layers,
                color_by,
                size,
                &skeleton,
            );
            diag.stats.upload_ms += v.last_upload_ms;
            diag.stats.render_ms += v.last_render_ms;
            match result {
                Ok(t) => Some(t),
                Err(e) => {
                    let message = e.to_string();
                    if views.render_error.as_deref() != Some(message.as_str()) {
                        diag.log.error(format!("drawing the view: {message}"));
                        views.render_error = Some(message);
                    }
                    None
                }
            }
        }
        None => None,
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
    let projection = views.projection(view);
    crate::overlay::overlay_ui(
        &painter,
        rect,
        view,
        &projection,
        &doc.session,
        &skeleton,
        tools,
    );
}
