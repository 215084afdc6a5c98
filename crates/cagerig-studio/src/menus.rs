//! The menu bar (File, Edit, View, Help) and the dialogs it opens: open / save / export with a
//! small file browser, animation import / export, the recovery offer, and the shortcut list.

use std::path::{Path, PathBuf};

use cagerig_render::CameraPreset;

use crate::app::{CURRENT, Layout, REST, StudioApp};
use crate::document::Command;
use crate::keys::Track;
use crate::opening::{AfterConfirm, OpenRequest};

/// The shortcuts, for Help ▸ Shortcuts.
pub const SHORTCUTS: &[(&str, &str)] = &[
    (
        "Left click",
        "select a cage vertex or a joint (Shift adds, Ctrl removes)",
    ),
    (
        "Left drag on empty space",
        "box-select cage vertices (Shift adds, Ctrl removes)",
    ),
    (
        "Left drag on a selected vertex",
        "move / rotate / scale the cage selection (tool)",
    ),
    (
        "Left drag on a joint",
        "rotate it freely (trackball; current view)",
    ),
    (
        "Gizmo arrow / ring",
        "move / scale along, or rotate about, one axis",
    ),
    ("Middle drag, Alt+left drag", "orbit"),
    ("Shift+middle, right drag", "pan"),
    ("Wheel, pinch", "zoom"),
    (
        "G / R / S",
        "grab / rotate / scale the selection under the mouse",
    ),
    (
        "  then X / Y / Z",
        "constrain to an axis (Shift: to the plane normal to the axis)",
    ),
    (
        "  then digits, -, Backspace",
        "type a distance, degrees or a factor",
    ),
    (
        "  then Enter / left click",
        "confirm; Esc / right click cancels",
    ),
    ("W / E / T", "tool: move / rotate / scale"),
    ("F", "frame the rig in the view under the mouse"),
    ("A / Alt+A", "select all cage vertices / none"),
    (
        "K / Shift+K",
        "key the current pose / the rest cage at the playhead",
    ),
    ("Space", "play / pause"),
    ("Delete", "delete the selected key"),
    ("Ctrl+Z / Ctrl+Shift+Z", "undo / redo"),
    (
        "Ctrl+O / Ctrl+S / Ctrl+Shift+S",
        "open / save session / save session as",
    ),
];

/// The menu bar.
pub fn menu_bar_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    egui::Panel::top("menu").show(ui, |ui| {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| file_menu_ui(app, ui));
            ui.menu_button("Edit", |ui| edit_menu_ui(app, ui));
            ui.menu_button("View", |ui| view_menu_ui(app, ui));
            ui.menu_button("Help", |ui| {
                if ui.button("Shortcuts").clicked() {
                    app.dialogs.help = true;
                }
            });
        });
    });
}

/// The answers to the unsaved-edits question.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum Answer {
    Save,
    Discard,
    Cancel,
}

impl Answer {
    fn label(self) -> &'static str {
        match self {
            Answer::Save => "Save",
            Answer::Discard => "Don't save",
            Answer::Cancel => "Cancel",
        }
    }
}

fn cwd_string() -> String {
    std::env::current_dir()
        .map(|d| format!("{}/", d.display()))
        .unwrap_or_default()
}

fn file_menu_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    if ui.button("Open… (Ctrl+O)").clicked() {
        app.dialogs.open = Some(cwd_string());
    }
    let recent = app.state_dir.recent();
    ui.add_enabled_ui(!recent.is_empty(), |ui| {
        ui.menu_button("Open recent", |ui| {
            for path in recent {
                if ui.button(path.display().to_string()).clicked() {
                    app.open_path(&path);
                }
            }
        });
    });
    ui.menu_button("Open built-in demo", |ui| {
        for name in cagerig::demo::builtin_names() {
            if ui.button(*name).clicked() {
                app.request_open(OpenRequest::Rig(crate::rig_open::RigSource::Builtin {
                    name: (*name).to_string(),
                    resolution: None,
                }));
            }
        }
    });
    ui.separator();
    if ui.button("Save session (Ctrl+S)").clicked() {
        app.save();
    }
    if ui.button("Save session as… (Ctrl+Shift+S)").clicked() {
        app.dialogs.save_as = Some(format!("{}session.cagerig", cwd_string()));
    }
    ui.separator();
    if ui
        .button("Export meshes, cages, joints, keys, glTF…")
        .clicked()
    {
        app.dialogs.export_dir = Some(format!("{}cagerig-export", cwd_string()));
    }
    let names: Vec<String> = app.animations.iter().map(|a| a.name.clone()).collect();
    ui.add_enabled_ui(!names.is_empty(), |ui| {
        ui.menu_button("Load animation of the character", |ui| {
            for (i, name) in names.iter().enumerate() {
                if ui.button(name).clicked() {
                    app.load_character_animation(i);
                }
            }
        });
    });
    if ui.button("Import skeleton animation…").clicked() {
        app.dialogs.import_animation = Some((Track::Skeleton, cwd_string()));
    }
    if ui.button("Import cage animation…").clicked() {
        app.dialogs.import_animation = Some((Track::Cage, cwd_string()));
    }
    ui.separator();
    if ui.button("Quit").clicked() {
        app.quit_requested = true;
    }
}

fn edit_menu_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    let (undo, redo) = app.doc.as_ref().map_or((None, None), |d| {
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
        app.undo();
    }
    if ui
        .add_enabled(
            redo.is_some(),
            egui::Button::new(format!("Redo {} (Ctrl+Shift+Z)", redo.unwrap_or_default())),
        )
        .clicked()
    {
        app.redo();
    }
    ui.separator();
    if ui.button("Select all cage vertices (A)").clicked() {
        app.select_all();
    }
    if ui.button("Select none (Alt+A)").clicked() {
        app.selection = Default::default();
    }
    ui.separator();
    if ui.button("Reset pose").clicked() {
        app.run_command(&Command::ResetPose);
    }
}

fn view_menu_ui(app: &mut StudioApp, ui: &mut egui::Ui) {
    ui.radio_value(
        &mut app.layout,
        Layout::Split,
        "Current | rest side by side",
    );
    ui.radio_value(&mut app.layout, Layout::CurrentOnly, "Current pose only");
    ui.radio_value(&mut app.layout, Layout::RestOnly, "Rest pose only");
    ui.separator();
    for (label, preset) in [
        ("Front", CameraPreset::Front),
        ("Side", CameraPreset::Side),
        ("Top", CameraPreset::Top),
        ("Three-quarter", CameraPreset::ThreeQuarter),
    ] {
        if ui.button(format!("{label} (both views)")).clicked() {
            app.frame_views(Some(preset));
        }
    }
    if ui.button("Frame all (F)").clicked() {
        app.frame_views(None);
    }
}

impl StudioApp {
    pub fn frame_views(&mut self, preset: Option<CameraPreset>) {
        if let Some(doc) = &self.doc {
            for v in [CURRENT, REST] {
                self.views[v].frame_all(&doc.session, preset);
            }
        }
    }

    pub fn select_all(&mut self) {
        if let Some(doc) = &self.doc {
            self.selection.cage = (0..doc.session.rest_cage().len()).collect();
            self.selection.joint_is_active = false;
        }
    }

    pub fn undo(&mut self) {
        self.cancel_transform();
        let Some(doc) = &mut self.doc else { return };
        match doc.undo() {
            Ok(true) => {}
            Ok(false) => self.log_info("nothing to undo"),
            Err(e) => self.log_error(format!("undo: {e}")),
        }
    }

    pub fn redo(&mut self) {
        self.cancel_transform();
        let Some(doc) = &mut self.doc else { return };
        match doc.redo() {
            Ok(true) => {}
            Ok(false) => self.log_info("nothing to redo"),
            Err(e) => self.log_error(format!("redo: {e}")),
        }
    }

    /// Saves to the session's file, or asks for one.
    pub fn save(&mut self) {
        match self.session_path.clone() {
            Some(p) => {
                self.save_session_to(&p);
            }
            None => self.dialogs.save_as = Some(format!("{}session.cagerig", cwd_string())),
        }
    }
}

/// A path field with the entries of its folder below (click one to take it).
fn path_browser_ui(ui: &mut egui::Ui, path: &mut String) {
    ui.add(egui::TextEdit::singleline(path).desired_width(460.0));
    let p = Path::new(path.as_str());
    let dir: PathBuf = if p.is_dir() {
        p.to_path_buf()
    } else {
        p.parent()
            .map_or_else(|| PathBuf::from("."), Path::to_path_buf)
    };
    let mut entries: Vec<(bool, String)> = std::fs::read_dir(&dir)
        .map(|rd| {
            rd.filter_map(Result::ok)
                .map(|e| {
                    (
                        e.path().is_dir(),
                        e.file_name().to_string_lossy().into_owned(),
                    )
                })
                .filter(|(_, n)| !n.starts_with('.'))
                .collect()
        })
        .unwrap_or_default();
    entries.sort_by(|a, b| b.0.cmp(&a.0).then(a.1.cmp(&b.1)));
    egui::ScrollArea::vertical()
        .max_height(220.0)
        .show(ui, |ui| {
            if ui.small_button(".. (up)").clicked()
                && let Some(parent) = dir.parent()
            {
                *path = format!("{}/", parent.display());
            }
            for (is_dir, name) in entries {
                let label = if is_dir {
                    format!("{name}/")
                } else {
                    name.clone()
                };
                if ui.small_button(label).clicked() {
                    let joined = dir.join(&name);
                    *path = if is_dir {
                        format!("{}/", joined.display())
                    } else {
                        joined.display().to_string()
                    };
                }
            }
        });
}

/// What a path window's buttons asked for.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum PathAction {
    None,
    Act,
    Cancel,
}

/// A window with an explanation, a path field with its folder's entries, `extra` widgets, and
/// an action button and Cancel.
fn path_window_ui(
    ctx: &egui::Context,
    title: &str,
    note: Option<&str>,
    path: &mut String,
    action: &str,
    extra: impl FnOnce(&mut egui::Ui),
) -> PathAction {
    let mut clicked = PathAction::None;
    egui::Window::new(title).collapsible(false).show(ctx, |ui| {
        if let Some(note) = note {
            ui.label(note);
        }
        path_browser_ui(ui, path);
        extra(ui);
        ui.horizontal(|ui| {
            if ui.button(action).clicked() {
                clicked = PathAction::Act;
            }
            if ui.button("Cancel").clicked() {
                clicked = PathAction::Cancel;
            }
        });
    });
    clicked
}

/// The dialogs.
pub fn dialogs_ui(app: &mut StudioApp, ctx: &egui::Context) {
    if let Some(mut path) = app.dialogs.open.take() {
        let dialogs = &mut app.dialogs;
        let action = path_window_ui(
            ctx,
            "Open",
            Some("A character (.obj with companions, .glb, .gltf, .fbx) or a session (.cagerig)"),
            &mut path,
            "Open",
            |ui| {
                ui.horizontal(|ui| {
                    ui.checkbox(
                        &mut dialogs.generate_cage,
                        "Generate a cage if the character has none, with",
                    );
                    if dialogs.cage_vertices == 0 {
                        dialogs.cage_vertices = 100;
                    }
                    ui.add(
                        egui::DragValue::new(&mut dialogs.cage_vertices)
                            .range(8..=5000)
                            .suffix(" vertices"),
                    );
                });
            },
        );
        match action {
            PathAction::Act => app.open_path(Path::new(path.trim())),
            PathAction::None => app.dialogs.open = Some(path),
            PathAction::Cancel => {}
        }
    }
    if let Some(mut path) = app.dialogs.save_as.take() {
        let action = path_window_ui(ctx, "Save session as", None, &mut path, "Save", |_| {});
        let saved = action == PathAction::Act && app.save_session_to(Path::new(path.trim()));
        if action == PathAction::None || (action == PathAction::Act && !saved) {
            app.dialogs.save_as = Some(path);
        } else if let (true, Some(after)) = (saved, app.dialogs.after_save.take()) {
            app.continue_after_confirm(ctx, after);
        }
    }
    if let Some(after) = app.dialogs.confirm.take() {
        let title = match &after {
            AfterConfirm::Close => "Save changes before closing?".to_string(),
            AfterConfirm::Open(request) => {
                format!("Save changes before opening {}?", request.display_name())
            }
        };
        let mut answer = None;
        egui::Window::new(title)
            .collapsible(false)
            .resizable(false)
            .show(ctx, |ui| {
                ui.label("The edits since the last save are not in a session file.");
                ui.horizontal(|ui| {
                    for choice in [Answer::Save, Answer::Discard, Answer::Cancel] {
                        if ui.button(choice.label()).clicked() {
                            answer = Some(choice);
                        }
                    }
                });
            });
        match answer {
            None => app.dialogs.confirm = Some(after),
            Some(Answer::Save) => match app.session_path.clone() {
                Some(path) => {
                    if app.save_session_to(&path) {
                        app.continue_after_confirm(ctx, after);
                    }
                }
                None => {
                    app.dialogs.save_as = Some(format!("{}session.cagerig", cwd_string()));
                    app.dialogs.after_save = Some(after);
                }
            },
            Some(Answer::Discard) => app.continue_after_confirm(ctx, after),
            Some(Answer::Cancel) => {}
        }
    }
    if let Some(mut path) = app.dialogs.export_dir.take() {
        let note = "Folder for mesh_rest.obj, mesh_posed.obj, cage_rest.obj, cage_posed.obj, \
                    joints.json, the animation files of the keys and rig.glb";
        match path_window_ui(ctx, "Export", Some(note), &mut path, "Export", |_| {}) {
            PathAction::Act => app.export_to(Path::new(path.trim())),
            PathAction::None => app.dialogs.export_dir = Some(path),
            PathAction::Cancel => {}
        }
    }
    if let Some((track, mut path)) = app.dialogs.import_animation.take() {
        let title = match track {
            Track::Skeleton => "Import skeleton animation",
            Track::Cage => "Import cage animation",
        };
        match path_window_ui(ctx, title, None, &mut path, "Import", |_| {}) {
            PathAction::Act => app.import_animation(track, Path::new(path.trim())),
            PathAction::None => app.dialogs.import_animation = Some((track, path)),
            PathAction::Cancel => {}
        }
    }
    if let Some(path) = app.dialogs.recovery.clone() {
        egui::Window::new("Recover unsaved work?")
            .collapsible(false)
            .show(ctx, |ui| {
                ui.label(format!(
                    "The last session did not end cleanly; its autosave is in {}.",
                    path.display()
                ));
                ui.horizontal(|ui| {
                    if ui.button("Recover").clicked() {
                        app.start_open(OpenRequest::Recovery(path.clone()));
                        app.dialogs.recovery = None;
                    }
                    if ui.button("Discard").clicked() {
                        app.state_dir.clear_recovery();
                        app.dialogs.recovery = None;
                    }
                });
            });
    }
    if app.dialogs.help {
        let mut open = true;
        egui::Window::new("Shortcuts")
            .open(&mut open)
            .show(ctx, |ui| {
                egui::Grid::new("shortcuts").striped(true).show(ui, |ui| {
                    for (keys, what) in SHORTCUTS {
                        ui.label(*keys);
                        ui.label(*what);
                        ui.end_row();
                    }
                });
            });
        app.dialogs.help = open;
    }
}

impl StudioApp {
    pub fn export_to(&mut self, dir: &Path) {
        let Some(doc) = &self.doc else { return };
        match crate::export::export_all(doc, dir) {
            Ok(files) => self.log_info(format!(
                "exported {} files to {}",
                files.len(),
                dir.display()
            )),
            Err(e) => self.log_error(format!("export: {e}")),
        }
    }

    /// Puts animation `index` of the glTF / FBX character on the skeleton track (one undo step).
    pub fn load_character_animation(&mut self, index: usize) {
        let Some(animation) = self.animations.get(index) else {
            return;
        };
        let name = animation.name.clone();
        let Some(doc) = &mut self.doc else { return };
        let mut snapshot = doc.snapshot();
        let n = snapshot
            .keys
            .set_skeleton_track(&animation.track, &doc.session);
        // Morph weights (a cagerig export with a cage track): cage keys, SkelUp held.
        let mut cage_note = String::new();
        let mut warning = None;
        if let Some(weights) = &animation.morph_weights {
            match cagerig_formats::morph_cage_track(
                &doc.session,
                &self.morph_targets,
                &animation.track,
                weights,
            ) {
                Ok(fit) => {
                    let count = snapshot.keys.set_cage_track(&fit.track, &doc.session);
                    snapshot.keys.hold_rest_skeleton = true;
                    cage_note = format!(
                        " and {count} cage keys from its morph weights (SkelUp held during \
                         playback: the joint keys carry the rest joints' motion)"
                    );
                    warning = fit.warning().map(|w| format!("animation {name:?}: {w}"));
                }
                Err(e) => {
                    warning = Some(format!(
                        "animation {name:?}: its morph weights could not be played as cage keys: \
                         {e}"
                    ))
                }
            }
        }
        let restored = doc.restore_as_step("load animation", &snapshot);
        if let Some(w) = warning {
            self.log_warning(w);
        }
        match restored {
            Ok(()) => {
                self.timeline.time = 0.0;
                self.log_info(format!("animation {name:?}: {n} skeleton keys{cage_note}"));
            }
            Err(e) => self.log_error(format!("animation {name:?}: {e}")),
        }
    }

    /// Replaces a track's keys with an animation file of the paper's tool (one undo step).
    pub fn import_animation(&mut self, track: Track, path: &Path) {
        let Some(doc) = &mut self.doc else { return };
        let mut keys = doc.keys.clone();
        let result = match track {
            Track::Skeleton => keys.import_skeleton_animation(path, &doc.session),
            Track::Cage => keys.import_cage_animation(path, &doc.session),
        };
        match result {
            Ok(n) => {
                let mut snapshot = doc.snapshot();
                snapshot.keys = keys;
                match doc.restore_as_step("import animation", &snapshot) {
                    Ok(()) => self.log_info(format!("{n} keys imported from {}", path.display())),
                    Err(e) => self.log_error(format!("{}: {e}", path.display())),
                }
            }
            Err(e) => self.log_error(e.to_string()),
        }
    }
}
