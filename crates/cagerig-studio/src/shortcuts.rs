//! Keyboard shortcuts of the whole window (undo / redo, files, selection, tools, keys, play);
//! the keys of the view under the mouse are in `view_keys`.

use egui::{Key, KeyboardShortcut, Modifiers};

use crate::action::Action;
use crate::dialogs::Dialogs;
use crate::keys::Track;
use crate::selection::Tool;

fn pressed(ctx: &egui::Context, modifiers: Modifiers, key: Key) -> bool {
    ctx.input_mut(|i| i.consume_shortcut(&KeyboardShortcut::new(modifiers, key)))
}

/// The shortcuts of the document and its files: undo / redo, save, open (the caller skips
/// them while a text field has the focus). Dialogs are opened here; the rest is returned.
/// In the web edition (`page_files`), Ctrl+O opens the page's file chooser and Ctrl+Shift+S
/// downloads the session as Ctrl+S does.
pub fn document_shortcuts(
    ctx: &egui::Context,
    dialogs: &mut Dialogs,
    page_files: bool,
) -> Vec<Action> {
    let mut actions = Vec::new();
    let ctrl_shift = Modifiers::COMMAND | Modifiers::SHIFT;
    if pressed(ctx, ctrl_shift, Key::Z) || pressed(ctx, Modifiers::COMMAND, Key::Y) {
        actions.push(Action::Redo);
    } else if pressed(ctx, Modifiers::COMMAND, Key::Z) {
        actions.push(Action::Undo);
    }
    if pressed(ctx, ctrl_shift, Key::S) {
        if page_files {
            actions.push(Action::Save);
        } else {
            dialogs.save_as = Some("session.cagerig".into());
        }
    } else if pressed(ctx, Modifiers::COMMAND, Key::S) {
        actions.push(Action::Save);
    }
    if pressed(ctx, Modifiers::COMMAND, Key::O) {
        if page_files {
            actions.push(Action::ChooseCharacter);
        } else {
            dialogs.open = Some(String::new());
        }
    }
    actions
}

/// The editing shortcuts: selection, keys, play, tools (the caller skips them during a
/// transform, whose keys are the view's, and while a text field has the focus).
pub fn editing_shortcuts(ctx: &egui::Context) -> Vec<Action> {
    let mut actions = Vec::new();
    if pressed(ctx, Modifiers::ALT, Key::A) {
        actions.push(Action::SelectNone);
    } else if pressed(ctx, Modifiers::NONE, Key::A) {
        actions.push(Action::SelectAll);
    }
    if pressed(ctx, Modifiers::SHIFT, Key::K) {
        actions.push(Action::SetKey(Track::Cage));
    } else if pressed(ctx, Modifiers::NONE, Key::K) {
        actions.push(Action::SetKey(Track::Skeleton));
    }
    if pressed(ctx, Modifiers::NONE, Key::Space) {
        actions.push(Action::TogglePlay);
    }
    if pressed(ctx, Modifiers::NONE, Key::Delete) {
        actions.push(Action::DeleteSelectedKey);
    }
    for (key, tool) in [
        (Key::W, Tool::Move),
        (Key::E, Tool::Rotate),
        (Key::T, Tool::Scale),
    ] {
        if pressed(ctx, Modifiers::NONE, key) {
            actions.push(Action::SetTool(tool));
        }
    }
    actions
}
