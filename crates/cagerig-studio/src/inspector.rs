//! The side panel: layers, colour maps, the tool, skinning and the sync locks, and numeric
//! entry for the selection (joint rotation in Euler degrees, cage offsets).

use cagerig::session::SyncLocks;
use cagerig::skinning::SkinningMethod;
use glam::{DQuat, DVec3, EulerRot};

use crate::app::{ColorMode, StudioApp, Tool};
use crate::document::Command;

/// Numeric-entry fields kept between frames.
#[derive(Debug, Clone, Default)]
pub struct NumericEntry {
    /// Offset applied to the cage selection by "Move by".
    pub offset: [f64; 3],
    /// Whether the Euler drag values are being dragged (one undo step per drag).
    euler_dragging: bool,
}

/// The right-hand panel.
pub fn inspector_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    egui::Panel::right("inspector")
        .resizable(true)
        .default_size(260.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                display_ui(app, ui);
                ui.separator();
                rig_ui(app, ui);
                ui.separator();
                selection_ui(app, ui);
            });
        });
}

fn display_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    ui.heading("Display");
    ui.horizontal_wrapped(|ui| {
        ui.checkbox(&mut app.layers.mesh, "Mesh");
        ui.checkbox(&mut app.layers.wireframe, "Wireframe");
        ui.checkbox(&mut app.layers.cage, "Cage");
        ui.checkbox(&mut app.layers.skeleton, "Skeleton");
        ui.checkbox(&mut app.layers.flat, "Flat");
        ui.checkbox(&mut app.layers.ground, "Ground");
    });
    ui.label("Colour map");
    ui.radio_value(&mut app.color_mode, ColorMode::None, "None");
    ui.radio_value(
        &mut app.color_mode,
        ColorMode::Weights,
        "Skin weights Ω of the joint",
    );
    ui.radio_value(
        &mut app.color_mode,
        ColorMode::CageCoords,
        "Φ of the cage vertex",
    );
    ui.radio_value(
        &mut app.color_mode,
        ColorMode::JointCoords,
        "Ψ of the joint (cage)",
    );
    if app.color_mode != ColorMode::None
        && app.color_by() == cagerig_render::rig_scene::ColorBy::None
    {
        ui.weak(match app.color_mode {
            ColorMode::CageCoords => "select a cage vertex to see its map",
            _ => "select a joint to see its map",
        });
    }
}

fn rig_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    ui.heading("Rig");
    ui.horizontal(|ui| {
        ui.label("Tool");
        ui.selectable_value(&mut app.tool, Tool::Move, "Move (W)");
        ui.selectable_value(&mut app.tool, Tool::Rotate, "Rotate (E)");
        ui.selectable_value(&mut app.tool, Tool::Scale, "Scale (T)");
    });
    let Some(doc) = &app.doc else { return };
    let method = doc.session.skinning();
    let locks = doc.session.sync_locks();
    ui.horizontal(|ui| {
        ui.label("Skinning");
        for m in SkinningMethod::ALL {
            if ui.selectable_label(method == m, m.label()).clicked() && method != m {
                app.run_command(&Command::SetSkinning(m));
            }
        }
    });
    let mut new_locks = locks;
    ui.checkbox(
        &mut new_locks.skel_up,
        "Lock SkelUp (rest skeleton ignores the cage)",
    );
    ui.checkbox(
        &mut new_locks.cage_up,
        "Lock CageUp (current cage ignores the pose)",
    );
    if new_locks != locks {
        app.run_command(&Command::SetLocks(new_locks));
    }
    if new_locks != SyncLocks::default() {
        ui.colored_label(
            egui::Color32::from_rgb(200, 30, 30),
            "Warning: a lock is on: the structures are out of sync until it is off.",
        );
    }
    if ui.button("Reset pose").clicked() {
        app.run_command(&Command::ResetPose);
    }
}

fn selection_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    ui.heading("Selection");
    let Some(doc) = &app.doc else { return };
    let s = &doc.session;
    if let Some(j) = app.selection.joint {
        let joint = s.skeleton().joint(j);
        ui.label(format!("Joint {j}: {}", joint.name));
        let q = s.posed_local_rotations()[j];
        let (x, y, z) = q.to_euler(EulerRot::XYZ);
        // `+ 0.0` shows a negative zero as 0.
        let mut euler = [x, y, z].map(|a| a.to_degrees() + 0.0);
        let mut changed = false;
        let mut started = false;
        let mut stopped = false;
        ui.horizontal(|ui| {
            ui.label("Local rotation XYZ°");
            for v in &mut euler {
                let r = ui.add(egui::DragValue::new(v).speed(0.5).max_decimals(3));
                changed |= r.changed();
                started |= r.drag_started();
                stopped |= r.drag_stopped() || r.lost_focus();
            }
        });
        if changed {
            let rotation = DQuat::from_euler(
                EulerRot::XYZ,
                euler[0].to_radians(),
                euler[1].to_radians(),
                euler[2].to_radians(),
            );
            let command = Command::SetJointRotation { joint: j, rotation };
            if started || app.numeric.euler_dragging {
                app.numeric.euler_dragging = true;
                if let Some(doc) = &mut app.doc {
                    doc.begin_gesture("rotate joint (numeric)");
                    if let Err(e) = doc.gesture_event(&command) {
                        app.log_error(format!("rotate joint: {e}"));
                    }
                }
            } else {
                app.run_command(&command);
            }
        }
        if stopped && app.numeric.euler_dragging {
            app.numeric.euler_dragging = false;
            if let Some(doc) = &mut app.doc {
                doc.end_gesture();
            }
        }
    }
    let Some(doc) = &app.doc else { return };
    let n = app.selection.cage.len();
    if n == 0 {
        ui.weak("Click a cage vertex or a joint in a view (box-drag for several).");
        return;
    }
    ui.label(format!("{n} cage vertices"));
    if n == 1
        && let Some(&k) = app.selection.cage.first()
    {
        let c = doc.session.rest_cage()[k];
        let p = doc.session.posed_cage()[k];
        ui.label(format!("C[{k}] = ({:.4}, {:.4}, {:.4})", c.x, c.y, c.z));
        ui.label(format!("C'[{k}] = ({:.4}, {:.4}, {:.4})", p.x, p.y, p.z));
    }
    ui.horizontal(|ui| {
        ui.label("Offset");
        for v in &mut app.numeric.offset {
            ui.add(egui::DragValue::new(v).speed(0.01).max_decimals(5));
        }
    });
    let offset = DVec3::from_array(app.numeric.offset);
    let vertices: Vec<usize> = app.selection.cage.iter().copied().collect();
    ui.horizontal(|ui| {
        if ui.button("Move rest cage C").clicked() {
            app.run_command(&Command::MoveRestCage {
                vertices: vertices.clone(),
                offsets: vec![offset],
            });
        }
        if ui.button("Move current cage C'").clicked() {
            app.run_command(&Command::MovePosedCage {
                vertices,
                offsets: vec![offset],
            });
        }
    });
}
