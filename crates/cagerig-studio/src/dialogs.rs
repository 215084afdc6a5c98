//! The dialogs: open / save / export with a small file browser, animation import, the
//! unsaved-edits question, the recovery offer, and the shortcut list (Help ▸ Shortcuts).
//! What they ask for beyond their own fields is returned as [`Action`]s.

use std::path::{Path, PathBuf};

use crate::action::Action;
use crate::keys::Track;
use crate::opening::{AfterConfirm, OpenRequest};

/// Text fields of the dialogs, and which are open.
#[derive(Debug, Clone, Default)]
pub struct Dialogs {
    pub open: Option<String>,
    pub save_as: Option<String>,
    pub export_dir: Option<String>,
    pub import_animation: Option<(Track, String)>,
    pub export_animation: Option<String>,
    pub help: bool,
    /// A recovery file offered at start.
    pub recovery: Option<PathBuf>,
    /// File > Open: generate a cage (of `cage_vertices` vertices) when the character has none.
    pub generate_cage: bool,
    pub cage_vertices: usize,
    /// File > Open: the skin of a file with several (a name or an index; empty: the first, with
    /// the skins that share its skeleton).
    pub skin: String,
    /// Unsaved edits would be lost (by closing, or by opening something else): Save / Don't
    /// save / Cancel, then this.
    pub confirm: Option<AfterConfirm>,
    /// What to do once the Save-as dialog has saved (Save chosen without a session path).
    pub after_save: Option<AfterConfirm>,
    /// The user saved or discarded the edits in the close dialog: the window may close.
    pub close_approved: bool,
}

impl Dialogs {
    /// Opens the Save-as dialog on `session.cagerig` in the working folder.
    pub fn ask_save_as(&mut self) {
        self.save_as = Some(format!("{}session.cagerig", cwd_string()));
    }
}

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

/// The working folder with a trailing slash (empty if unknown).
pub fn cwd_string() -> String {
    std::env::current_dir()
        .map(|d| format!("{}/", d.display()))
        .unwrap_or_default()
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

/// The dialogs that are open; returns what they ask for, in order.
pub fn dialogs_ui(ctx: &egui::Context, dialogs: &mut Dialogs) -> Vec<Action> {
    let mut actions = Vec::new();
    if let Some(mut path) = dialogs.open.take() {
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
                ui.horizontal(|ui| {
                    ui.label("Skin (name or index; empty: the first)");
                    ui.add(egui::TextEdit::singleline(&mut dialogs.skin).desired_width(120.0));
                });
            },
        );
        match action {
            PathAction::Act => actions.push(Action::OpenPath(PathBuf::from(path.trim()))),
            PathAction::None => dialogs.open = Some(path),
            PathAction::Cancel => {}
        }
    }
    if let Some(mut path) = dialogs.save_as.take() {
        match path_window_ui(ctx, "Save session as", None, &mut path, "Save", |_| {}) {
            PathAction::Act => actions.push(Action::SaveAs(path)),
            PathAction::None => dialogs.save_as = Some(path),
            PathAction::Cancel => {}
        }
    }
    if let Some(after) = dialogs.confirm.take() {
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
            None => dialogs.confirm = Some(after),
            Some(Answer::Save) => actions.push(Action::SaveThenContinue(after)),
            Some(Answer::Discard) => actions.push(Action::Continue(after)),
            Some(Answer::Cancel) => {}
        }
    }
    if let Some(mut path) = dialogs.export_dir.take() {
        let note = "A new folder (or an earlier export, which is replaced) for mesh_rest.obj, \
                    mesh_posed.obj, cage_rest.obj, cage_posed.obj, joints.json, the animation \
                    files of the keys and the rig (rig.obj, .skt, .skw, rig_cage.obj, rig.glb); \
                    it appears complete or not at all";
        match path_window_ui(ctx, "Export", Some(note), &mut path, "Export", |_| {}) {
            PathAction::Act => actions.push(Action::Export(PathBuf::from(path.trim()))),
            PathAction::None => dialogs.export_dir = Some(path),
            PathAction::Cancel => {}
        }
    }
    if let Some((track, mut path)) = dialogs.import_animation.take() {
        let title = match track {
            Track::Skeleton => "Import skeleton animation",
            Track::Cage => "Import cage animation",
        };
        match path_window_ui(ctx, title, None, &mut path, "Import", |_| {}) {
            PathAction::Act => {
                actions.push(Action::ImportAnimation(track, PathBuf::from(path.trim())));
            }
            PathAction::None => dialogs.import_animation = Some((track, path)),
            PathAction::Cancel => {}
        }
    }
    if let Some(path) = dialogs.recovery.clone() {
        egui::Window::new("Recover unsaved work?")
            .collapsible(false)
            .show(ctx, |ui| {
                ui.label(format!(
                    "The last session did not end cleanly; its autosave is in {}.",
                    path.display()
                ));
                ui.horizontal(|ui| {
                    if ui.button("Recover").clicked() {
                        actions.push(Action::StartOpen(OpenRequest::Recovery(path.clone())));
                        dialogs.recovery = None;
                    }
                    if ui.button("Discard").clicked() {
                        actions.push(Action::DiscardRecovery);
                        dialogs.recovery = None;
                    }
                });
            });
    }
    if dialogs.help {
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
        dialogs.help = open;
    }
    actions
}
