//! The menu bar (File, Edit, View, Help). It opens the dialogs and sets the layout itself;
//! everything else it asks for is returned as [`Action`]s.

use cagerig_render::CameraPreset;

use crate::action::Action;
use crate::dialogs::{Dialogs, cwd_string};
use crate::document::Command;
use crate::keys::Track;
use crate::opening::OpenRequest;
use crate::page_files::PageFiles;
use crate::project::Project;
use crate::rig_open::RigSource;
use crate::view_state::Layout;

/// The menu bar; returns what its entries ask for, in order.
pub fn menu_bar_ui(
    ui: &mut egui::Ui,
    project: &Project,
    layout: &mut Layout,
    dialogs: &mut Dialogs,
    page_files: Option<&dyn PageFiles>,
) -> Vec<Action> {
    let mut actions = Vec::new();
    egui::Panel::top("menu").show(ui, |ui| {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| match page_files {
                None => file_menu_ui(ui, project, dialogs, &mut actions),
                Some(page) => page_file_menu_ui(ui, project, page, &mut actions),
            });
            ui.menu_button("Edit", |ui| edit_menu_ui(ui, project, &mut actions));
            ui.menu_button("View", |ui| view_menu_ui(ui, layout, &mut actions));
            ui.menu_button("Help", |ui| {
                if ui.button("Shortcuts").clicked() {
                    dialogs.help = true;
                }
            });
        });
    });
    actions
}

fn file_menu_ui(
    ui: &mut egui::Ui,
    project: &Project,
    dialogs: &mut Dialogs,
    actions: &mut Vec<Action>,
) {
    if ui.button("Open… (Ctrl+O)").clicked() {
        dialogs.open = Some(cwd_string());
    }
    let recent = project.state_dir.recent();
    ui.add_enabled_ui(!recent.is_empty(), |ui| {
        ui.menu_button("Open recent", |ui| {
            for path in recent {
                if ui.button(path.display().to_string()).clicked() {
                    actions.push(Action::OpenPath(path));
                }
            }
        });
    });
    ui.menu_button("Open built-in demo", |ui| builtin_rigs_ui(ui, "", actions));
    ui.separator();
    if ui.button("Save session (Ctrl+S)").clicked() {
        actions.push(Action::Save);
    }
    if ui.button("Save session as… (Ctrl+Shift+S)").clicked() {
        dialogs.ask_save_as();
    }
    ui.separator();
    if ui
        .button("Export meshes, cages, joints, keys, glTF…")
        .clicked()
    {
        dialogs.export_dir = Some(format!("{}cagerig-export", cwd_string()));
    }
    character_animations_ui(ui, project, actions);
    if ui.button("Import skeleton animation…").clicked() {
        dialogs.import_animation = Some((Track::Skeleton, cwd_string()));
    }
    if ui.button("Import cage animation…").clicked() {
        dialogs.import_animation = Some((Track::Cage, cwd_string()));
    }
    ui.separator();
    if ui.button("Quit").clicked() {
        actions.push(Action::Quit);
    }
}

/// A button per built-in demo rig (its name and `suffix`), each asking to open it at its
/// default resolution.
fn builtin_rigs_ui(ui: &mut egui::Ui, suffix: &str, actions: &mut Vec<Action>) {
    for name in cagerig::demo::builtin_names() {
        if ui.button(format!("{name}{suffix}")).clicked() {
            actions.push(Action::RequestOpen(OpenRequest::Rig(RigSource::Builtin {
                name: (*name).to_string(),
                resolution: None,
            })));
        }
    }
}

/// The File menu of the web edition: the page's file chooser, the samples, downloads.
fn page_file_menu_ui(
    ui: &mut egui::Ui,
    project: &Project,
    page: &dyn PageFiles,
    actions: &mut Vec<Action>,
) {
    if ui.button("Open .glb / .gltf… (Ctrl+O)").clicked() {
        actions.push(Action::ChooseCharacter);
    }
    ui.menu_button("Open sample", |ui| {
        builtin_rigs_ui(ui, " (built-in)", actions);
        for name in page.samples() {
            if ui.button(&name).clicked() {
                actions.push(Action::OpenSample(name));
            }
        }
    });
    ui.separator();
    if ui.button("Download session (Ctrl+S)").clicked() {
        actions.push(Action::Save);
    }
    if ui.button("Download glTF (.glb)").clicked() {
        actions.push(Action::DownloadGlb);
    }
    character_animations_ui(ui, project, actions);
}

/// Load animation of the character ▸ (one entry per animation of a glTF / FBX character).
fn character_animations_ui(ui: &mut egui::Ui, project: &Project, actions: &mut Vec<Action>) {
    let names: Vec<String> = project.animations.iter().map(|a| a.name.clone()).collect();
    ui.add_enabled_ui(!names.is_empty(), |ui| {
        ui.menu_button("Load animation of the character", |ui| {
            for (i, name) in names.iter().enumerate() {
                if ui.button(name).clicked() {
                    actions.push(Action::LoadCharacterAnimation(i));
                }
            }
        });
    });
}

fn edit_menu_ui(ui: &mut egui::Ui, project: &Project, actions: &mut Vec<Action>) {
    let (undo, redo) = project.doc.as_ref().map_or((None, None), |d| {
        (
            d.history().undo_label().map(str::to_owned),
            d.history().redo_label().map(str::to_owned),
        )
    });
    if ui
        .add_enabled(
            undo.is_some(),
            egui::Button::new(format!("Undo {} (Ctrl+Z)", undo.unwrap_or_default())),
        )
        .clicked()
    {
        actions.push(Action::Undo);
    }
    if ui
        .add_enabled(
            redo.is_some(),
            egui::Button::new(format!("Redo {} (Ctrl+Shift+Z)", redo.unwrap_or_default())),
        )
        .clicked()
    {
        actions.push(Action::Redo);
    }
    ui.separator();
    if ui.button("Select all cage vertices (A)").clicked() {
        actions.push(Action::SelectAll);
    }
    if ui.button("Select none (Alt+A)").clicked() {
        actions.push(Action::SelectNone);
    }
    ui.separator();
    if ui.button("Reset pose").clicked() {
        actions.push(Action::Run(Command::ResetPose));
    }
}

fn view_menu_ui(ui: &mut egui::Ui, layout: &mut Layout, actions: &mut Vec<Action>) {
    ui.radio_value(layout, Layout::Split, "Current | rest side by side");
    ui.radio_value(layout, Layout::CurrentOnly, "Current pose only");
    ui.radio_value(layout, Layout::RestOnly, "Rest pose only");
    ui.separator();
    for (label, preset) in [
        ("Front", CameraPreset::Front),
        ("Side", CameraPreset::Side),
        ("Top", CameraPreset::Top),
        ("Three-quarter", CameraPreset::ThreeQuarter),
    ] {
        if ui.button(format!("{label} (both views)")).clicked() {
            actions.push(Action::FrameViews(Some(preset)));
        }
    }
    if ui.button("Frame all (F)").clicked() {
        actions.push(Action::FrameViews(None));
    }
}
