//! The side panel: layers, colour maps, the tool, skinning and the sync locks, and numeric
//! entry for the selection (joint rotation in Euler degrees, cage offsets).

use cagerig::session::SyncLocks;
use cagerig::skinning::SkinningMethod;
use glam::{DQuat, DVec3, EulerRot};

use crate::diagnostics::Diagnostics;
use crate::doc_commands::run_command;
use crate::document::{Command, Document};
use crate::selection::{Selection, Tool};
use crate::tools::{NumericEntry, Tools};
use crate::view_state::{ColorMode, ViewState};

/// The right-hand panel (`offload`: what computes a Bind's automatic weights, when not the
/// bind's own thread).
pub fn inspector_ui(
    ui: &mut egui::Ui,
    mut doc: Option<&mut Document>,
    view: &mut ViewState,
    tools: &mut Tools,
    diag: &mut Diagnostics,
    offload: Option<&dyn crate::offload::WeightsOffload>,
) {
    egui::Panel::right("inspector")
        .resizable(true)
        .default_size(260.0)
        .show(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                display_ui(ui, view, &tools.selection);
                ui.separator();
                rig_ui(ui, doc.as_deref_mut(), &mut tools.tool, diag);
                ui.separator();
                selection_ui(
                    ui,
                    doc.as_deref_mut(),
                    &tools.selection,
                    &mut tools.numeric,
                    diag,
                );
                ui.separator();
                crate::skeleton_panel::skeleton_ui(ui, doc, tools, diag, offload);
            });
        });
}

fn display_ui(ui: &mut egui::Ui, view: &mut ViewState, selection: &Selection) {
    ui.heading("Display");
    ui.horizontal_wrapped(|ui| {
        ui.checkbox(&mut view.layers.mesh, "Mesh");
        ui.checkbox(&mut view.layers.wireframe, "Wireframe");
        ui.checkbox(&mut view.layers.cage, "Cage");
        ui.checkbox(&mut view.layers.skeleton, "Skeleton");
        ui.checkbox(&mut view.layers.flat, "Flat");
        ui.checkbox(&mut view.layers.ground, "Ground");
    });
    ui.label("Colour map");
    ui.horizontal(|ui| {
        ui.radio_value(&mut view.color_mode, ColorMode::None, "None");
        ui.radio_value(
            &mut view.color_mode,
            ColorMode::CageReach,
            "Cage handles far from the body",
        )
        .on_hover_text(
            "Each cage handle's distance from the skin, over the rest cage's largest: the usual \
             colour up to 1, red from 2.5",
        );
    });
    ui.radio_value(
        &mut view.color_mode,
        ColorMode::Weights,
        "Skin weights Ω of the joint",
    );
    ui.radio_value(
        &mut view.color_mode,
        ColorMode::CageCoords,
        "Φ of the cage vertex",
    );
    ui.radio_value(
        &mut view.color_mode,
        ColorMode::JointCoords,
        "Ψ of the joint (cage)",
    );
    if view.color_by(selection) == cagerig_render::rig_scene::ColorBy::None {
        // The maps of a selection say what to select; the others need none.
        let hint = match view.color_mode {
            ColorMode::CageCoords => Some("select a cage vertex to see its map"),
            ColorMode::Weights | ColorMode::JointCoords => Some("select a joint to see its map"),
            ColorMode::None | ColorMode::CageReach => None,
        };
        if let Some(hint) = hint {
            ui.weak(hint);
        }
    }
}

fn rig_ui(ui: &mut egui::Ui, doc: Option<&mut Document>, tool: &mut Tool, diag: &mut Diagnostics) {
    ui.heading("Rig");
    ui.horizontal(|ui| {
        ui.label("Tool");
        ui.selectable_value(tool, Tool::Move, "Move (W)");
        ui.selectable_value(tool, Tool::Rotate, "Rotate (E)");
        ui.selectable_value(tool, Tool::Scale, "Scale (T)");
    });
    let Some(doc) = doc else { return };
    let method = doc.session.skinning();
    let locks = doc.session.sync_locks();
    ui.horizontal(|ui| {
        ui.label("Skinning");
        let has_blend_weights = doc.session.dq_blend_weights().is_some();
        for m in SkinningMethod::ALL {
            // The blended method reads the rig's DQ blend weights (FBX skins carry them).
            let available = !m.needs_dq_blend_weights() || has_blend_weights;
            let clicked = ui
                .add_enabled_ui(available, |ui| ui.selectable_label(method == m, m.label()))
                .inner
                .on_disabled_hover_text(
                    "This rig has no per-vertex DQ blend weights (FBX characters carry them)",
                )
                .clicked();
            if clicked && method != m {
                run_command(doc, &Command::SetSkinning(m), diag);
            }
        }
    });
    let coords = doc.session.coords_kind();
    ui.horizontal(|ui| {
        ui.label("Coordinates");
        for k in cagerig::CoordsKind::ALL {
            let label = match k {
                cagerig::CoordsKind::Mvc => "MVC",
                cagerig::CoordsKind::Green => "Green",
            };
            if ui
                .selectable_label(coords == k, label)
                .on_hover_text(format!(
                    "Bind with {} coordinates (keeps every edit)",
                    k.label()
                ))
                .clicked()
                && coords != k
            {
                run_command(doc, &Command::SetCoords(k), diag);
            }
        }
    });
    match coords {
        cagerig::CoordsKind::Mvc => cage_fit_ui(ui, doc, diag),
        cagerig::CoordsKind::Green => {
            cage_fit_ui(ui, doc, diag);
            face_term_ui(ui, doc, diag);
            unfitted_cage_ui(ui, doc, diag);
        }
    }
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
        run_command(doc, &Command::SetLocks(new_locks), diag);
    }
    if new_locks != SyncLocks::default() {
        ui.colored_label(
            egui::Color32::from_rgb(200, 30, 30),
            "Warning: a lock is on: the structures are out of sync until it is off.",
        );
    }
    if ui.button("Reset pose").clicked() {
        run_command(doc, &Command::ResetPose, diag);
    }
}

/// Green rigs: the stretched normals' face term
/// ([`cagerig::coords::stretched_normals::FaceTermKind`]); a change rebinds.
fn face_term_ui(ui: &mut egui::Ui, doc: &mut Document, diag: &mut Diagnostics) {
    use cagerig::coords::stretched_normals::FaceTermKind;
    let term = doc.session.green_face_term();
    ui.horizontal(|ui| {
        ui.label("Face term");
        for k in FaceTermKind::ALL {
            if ui
                .selectable_label(term == k, k.name())
                .on_hover_text(k.help())
                .clicked()
                && term != k
            {
                run_command(doc, &Command::SetGreenFaceTerm(k), diag);
            }
        }
    });
}

/// How CageUp fits the current cage C' ([`cagerig::CageFitKind`]).
fn cage_fit_ui(ui: &mut egui::Ui, doc: &mut Document, diag: &mut Diagnostics) {
    let fit = doc.session.requested_cage_fit();
    ui.horizontal(|ui| {
        ui.label("Current cage fit");
        for k in cagerig::CageFitKind::ALL {
            if ui
                .selectable_label(fit == k, k.name())
                .on_hover_text(k.help())
                .clicked()
                && fit != k
            {
                run_command(doc, &Command::SetCageFit(k), diag);
            }
        }
    });
}

/// Green rigs: the policy for poses the current cage cannot follow, and the state of C'.
fn unfitted_cage_ui(ui: &mut egui::Ui, doc: &mut Document, diag: &mut Diagnostics) {
    use cagerig::session::UnfittedCagePolicy;
    let policy = doc.session.unfitted_cage_policy();
    let mut keep = policy == UnfittedCagePolicy::KeepEvent;
    ui.checkbox(&mut keep, "Keep poses the current cage cannot follow")
        .on_hover_text(
            "Past a fold the Green current cage C' has no fit. Off: such an edit is refused. \
             On: it is kept (the skin and skeletons exact), C' is left unfitted and cannot be \
             grabbed until a pose fits again.",
        );
    let wanted = if keep {
        UnfittedCagePolicy::KeepEvent
    } else {
        UnfittedCagePolicy::Refuse
    };
    if wanted != policy {
        run_command(doc, &Command::SetUnfittedCage(wanted), diag);
    }
    if let Some(unfitted) = doc.session.posed_cage_unfitted() {
        ui.colored_label(
            egui::Color32::from_rgb(200, 30, 30),
            "The current cage is not fitted in this pose: it cannot be grabbed.",
        )
        .on_hover_text(unfitted.to_string());
    }
}

fn selection_ui(
    ui: &mut egui::Ui,
    doc: Option<&mut Document>,
    selection: &Selection,
    numeric: &mut NumericEntry,
    diag: &mut Diagnostics,
) {
    ui.heading("Selection");
    let Some(doc) = doc else { return };
    let s = &doc.session;
    // The selected joint's pose: only for a bound joint while the rig can be posed (a joint
    // of a skeleton being built is edited in the Skeleton panel).
    let posable = doc.check_posable().is_ok();
    if let Some(j) = selection
        .joint
        .filter(|&j| posable && j < s.skeleton().len())
    {
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
            if started || numeric.euler_dragging {
                numeric.euler_dragging = true;
                doc.begin_gesture("rotate joint (numeric)");
                if let Err(e) = doc.gesture_event(&command) {
                    diag.log.error(format!("rotate joint: {e}"));
                }
            } else {
                run_command(doc, &command, diag);
            }
        }
        if stopped && numeric.euler_dragging {
            numeric.euler_dragging = false;
            doc.end_gesture();
        }
    }
    let n = selection.cage.len();
    if n == 0 {
        ui.weak("Click a cage vertex or a joint in a view (box-drag for several).");
        return;
    }
    ui.label(format!("{n} cage vertices"));
    if n == 1
        && let Some(&k) = selection.cage.first()
    {
        let c = doc.session.rest_cage()[k];
        let p = doc.session.posed_cage()[k];
        ui.label(format!("C[{k}] = ({:.4}, {:.4}, {:.4})", c.x, c.y, c.z));
        ui.label(format!("C'[{k}] = ({:.4}, {:.4}, {:.4})", p.x, p.y, p.z));
    }
    ui.horizontal(|ui| {
        ui.label("Offset");
        for v in &mut numeric.offset {
            ui.add(egui::DragValue::new(v).speed(0.01).max_decimals(5));
        }
    });
    let offset = DVec3::from_array(numeric.offset);
    let vertices: Vec<usize> = selection.cage.iter().copied().collect();
    ui.horizontal(|ui| {
        if ui.button("Move rest cage C").clicked() {
            run_command(
                doc,
                &Command::MoveRestCage {
                    vertices: vertices.clone(),
                    offsets: vec![offset],
                },
                diag,
            );
        }
        if ui.button("Move current cage C'").clicked() {
            run_command(
                doc,
                &Command::MovePosedCage {
                    vertices,
                    offsets: vec![offset],
                },
                diag,
            );
        }
    });
}
