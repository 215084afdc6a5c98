//! The Skeleton panel: build or change the skeleton in the rest view — add joints by clicking
//! on the mesh, the X mirror, the joint list, renaming, re-parenting, adding a child, deleting
//! — and Bind it (automatic weights on a background thread, with progress).

use cagerig::auto_weights::{AutoWeightsOptions, TipJoints};
use glam::DVec3;

use crate::binding::BindWeights;
use crate::diagnostics::Diagnostics;
use crate::doc_commands::run_command;
use crate::document::{Command, Document, SkeletonEdit};
use crate::document_skeleton::ShownSkeleton;
use crate::offload::WeightsOffload;
use crate::tools::Tools;

/// The Skeleton section of the inspector.
/// `offload` computes a Bind's automatic weights when given (the web page's worker).
pub fn skeleton_ui(
    ui: &mut egui::Ui,
    doc: Option<&mut Document>,
    tools: &mut Tools,
    diag: &mut Diagnostics,
    offload: Option<&dyn WeightsOffload>,
) {
    let Some(doc) = doc else { return };
    // Open while a skeleton is being built; folded on a rigged character until asked for.
    let building = !doc.rigged() || doc.draft.is_some() || doc.bind_job().is_some();
    egui::CollapsingHeader::new(egui::RichText::new("Skeleton").heading())
        .id_salt("skeleton section")
        .open(building.then_some(true))
        .show(ui, |ui| skeleton_section_ui(ui, doc, tools, diag, offload));
}

fn skeleton_section_ui(
    ui: &mut egui::Ui,
    doc: &mut Document,
    tools: &mut Tools,
    diag: &mut Diagnostics,
    offload: Option<&dyn WeightsOffload>,
) {
    let skeleton = doc.shown_skeleton(true);
    let status = match (doc.draft.is_some(), doc.rigged()) {
        (_, false) if skeleton.positions.is_empty() => {
            "No skeleton yet: add joints by clicking on the mesh in the rest view, then Bind."
                .to_string()
        }
        (true, _) | (false, false) => format!(
            "{} joints — changes not bound yet: Bind to use them",
            skeleton.positions.len()
        ),
        (false, true) => format!("{} joints, bound", skeleton.positions.len()),
    };
    ui.label(status);
    bind_ui(ui, doc, diag, offload);
    ui.checkbox(&mut tools.add_joints, "Add joints by clicking")
        .on_hover_text(
            "In the rest view a click on the mesh adds a joint in the middle of the body under \
             the cursor, below the selected joint: successive clicks build a chain",
        );
    ui.checkbox(&mut doc.mirror_x, "X mirror (.L / .R)")
        .on_hover_text(
            "Joints added off the middle plane get a mirrored twin, named .L (+x) and .R; \
             moving or deleting one does the same to its twin",
        );
    joint_list_ui(ui, &skeleton, tools);
    selected_joint_ui(ui, doc, &skeleton, tools, diag);
}

fn depth(parents: &[Option<usize>], mut j: usize) -> usize {
    let mut d = 0;
    while let Some(Some(p)) = parents.get(j) {
        d += 1;
        j = *p;
        if d > parents.len() {
            break;
        }
    }
    d
}

fn joint_list_ui(ui: &mut egui::Ui, skeleton: &ShownSkeleton, tools: &mut Tools) {
    if skeleton.names.is_empty() {
        return;
    }
    egui::ScrollArea::vertical()
        .id_salt("joint list")
        .max_height(150.0)
        .show(ui, |ui| {
            for (j, name) in skeleton.names.iter().enumerate() {
                let indent = "   ".repeat(depth(&skeleton.parents, j).min(12));
                let selected = tools.selection.joint == Some(j);
                if ui
                    .selectable_label(selected, format!("{indent}{name}"))
                    .clicked()
                {
                    tools.selection.joint = Some(j);
                    tools.selection.joint_is_active = true;
                    tools.selection.cage.clear();
                }
            }
        });
}

fn selected_joint_ui(
    ui: &mut egui::Ui,
    doc: &mut Document,
    skeleton: &ShownSkeleton,
    tools: &mut Tools,
    diag: &mut Diagnostics,
) {
    let Some(j) = tools.selection.joint.filter(|&j| j < skeleton.names.len()) else {
        return;
    };
    let mut run = |doc: &mut Document, edit: SkeletonEdit| {
        run_command(doc, &Command::EditSkeleton(edit), diag)
    };
    ui.horizontal(|ui| {
        ui.label("Name");
        let buffer = match &mut tools.joint_name {
            Some((k, text)) if *k == j => text,
            slot => {
                *slot = Some((j, skeleton.names[j].clone()));
                match slot {
                    Some((_, text)) => text,
                    None => return,
                }
            }
        };
        // While the field is not being typed in it shows the joint's name (undo may change it).
        let id = ui.make_persistent_id("joint name");
        if !ui.memory(|m| m.has_focus(id)) && *buffer != skeleton.names[j] {
            buffer.clone_from(&skeleton.names[j]);
        }
        let response = ui.add(egui::TextEdit::singleline(buffer).id(id));
        if response.lost_focus() && *buffer != skeleton.names[j] {
            let name = buffer.clone();
            if !run(doc, SkeletonEdit::Rename { joint: j, name }) {
                tools.joint_name = None;
            }
        }
    });
    let parent = skeleton.parents[j];
    let parent_name = |p: Option<usize>| {
        p.and_then(|p| skeleton.names.get(p))
            .map_or("(root)".to_string(), Clone::clone)
    };
    let mut chosen = parent;
    egui::ComboBox::from_label("Parent")
        .selected_text(parent_name(parent))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut chosen, None, "(root)");
            for (k, name) in skeleton.names.iter().enumerate() {
                if k != j {
                    ui.selectable_value(&mut chosen, Some(k), name);
                }
            }
        });
    if chosen != parent {
        run(
            doc,
            SkeletonEdit::SetParent {
                joint: j,
                parent: chosen,
            },
        );
    }
    ui.horizontal(|ui| {
        if ui
            .button("Add child")
            .on_hover_text("A joint below this one, one bone length further along its bone")
            .clicked()
        {
            let position = child_position(skeleton, j, doc);
            let count = skeleton.positions.len();
            let mirror = doc.mirror_x.then(|| doc.mirror());
            if run(
                doc,
                SkeletonEdit::Add {
                    position,
                    parent: Some(j),
                    mirror,
                },
            ) {
                tools.selection.joint = Some(count);
            }
        }
        if ui.button("Delete").clicked() {
            let mirror = doc.mirror_x;
            if run(doc, SkeletonEdit::Delete { joint: j, mirror }) {
                tools.selection.joint = None;
            }
        }
    });
}

/// Where "Add child" puts a child of joint `j`: one bone further along the bone from its
/// parent, or a tenth of the rest mesh's height above a root.
fn child_position(skeleton: &ShownSkeleton, j: usize, doc: &Document) -> DVec3 {
    let at = skeleton.positions[j];
    let bone = skeleton.parents[j].map(|p| at - skeleton.positions[p]);
    match bone.filter(|b| b.length() > 0.0) {
        Some(b) => at + b,
        None => {
            let (lo, hi) = cagerig::mesh::bounding_box(doc.session.rest_mesh());
            at + DVec3::Y * 0.1 * (hi.y - lo.y).max(1e-9)
        }
    }
}

/// Starts a Bind of the document's skeleton (its draft, or the bound one re-weighted) with
/// automatic weights (the Skeleton panel's Bind), computed by `offload` when given; a refusal
/// goes to the log.
pub fn bind_automatic(
    doc: &mut Document,
    diag: &mut Diagnostics,
    offload: Option<&dyn WeightsOffload>,
) {
    let weights = BindWeights::Automatic(AutoWeightsOptions {
        tips: doc.bind_tips.clone(),
        ..AutoWeightsOptions::default()
    });
    if let Err(e) = doc.start_bind(weights, offload) {
        diag.log.error(format!("bind: {e}"));
    }
}

fn bind_ui(
    ui: &mut egui::Ui,
    doc: &mut Document,
    diag: &mut Diagnostics,
    offload: Option<&dyn WeightsOffload>,
) {
    if let Some(job) = doc.bind_job() {
        let (fraction, text) = job.progress();
        ui.add(egui::ProgressBar::new(fraction).text(text));
        ui.ctx().request_repaint();
        return;
    }
    ui.horizontal_wrapped(|ui| {
        let can_bind = doc.draft.as_ref().is_some_and(|d| !d.is_empty()) || doc.rigged();
        if ui
            .add_enabled(can_bind, egui::Button::new("Bind"))
            .on_hover_text(
                "Bind the skeleton with automatic weights (geodesic voxel binding): one undo step",
            )
            .clicked()
        {
            bind_automatic(doc, diag, offload);
        }
        if doc.draft.is_some()
            && doc.rigged()
            && ui
                .button("Apply, keep weights")
                .on_hover_text(
                    "Bind the changed skeleton keeping the bound weights (new joints get none)",
                )
                .clicked()
            && let Err(e) = doc.start_bind(BindWeights::KeepBound, None)
        {
            diag.log.error(format!("bind: {e}"));
        }
        if doc.draft.is_some() && ui.button("Discard changes").clicked() {
            run_command(doc, &Command::EditSkeleton(SkeletonEdit::Discard), diag);
        }
    });
    ui.horizontal(|ui| {
        ui.label("Tip joints deform").on_hover_text(
            "Which joints with no child get weight at Bind: all but end markers (names ending \
             in end, nub, tip or null), all, or none",
        );
        let tips = &mut doc.bind_tips;
        for (choice, label) in [
            (TipJoints::AllButEndMarkers, "Auto"),
            (TipJoints::All, "All"),
            (TipJoints::None, "None"),
        ] {
            if ui.selectable_label(*tips == choice, label).clicked() {
                *tips = choice;
            }
        }
    });
}
