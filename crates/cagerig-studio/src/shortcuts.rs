//! Keyboard shortcuts of the whole window (undo / redo, files, selection, tools, keys, play);
//! the keys of the view under the mouse are in `view_input`.

use egui::{Key, KeyboardShortcut, Modifiers};

use crate::app::{StudioApp, Tool};
use crate::keys::Track;

fn pressed(ctx: &egui::Context, modifiers: Modifiers, key: Key) -> bool {
    ctx.input_mut(|i| i.consume_shortcut(&KeyboardShortcut::new(modifiers, key)))
}

/// Handles the window-wide shortcuts (not while a text field has the focus).
pub fn global_shortcuts(app: &mut StudioApp, ctx: &egui::Context) {
    if ctx.memory(|m| m.focused().is_some()) {
        return;
    }
    let ctrl_shift = Modifiers::COMMAND | Modifiers::SHIFT;
    if pressed(ctx, ctrl_shift, Key::Z) || pressed(ctx, Modifiers::COMMAND, Key::Y) {
        app.redo();
    } else if pressed(ctx, Modifiers::COMMAND, Key::Z) {
        app.undo();
    }
    if pressed(ctx, ctrl_shift, Key::S) {
        app.dialogs.save_as = Some("session.cagerig".into());
    } else if pressed(ctx, Modifiers::COMMAND, Key::S) {
        app.save();
    }
    if pressed(ctx, Modifiers::COMMAND, Key::O) {
        app.dialogs.open = Some(String::new());
    }
    if app.interaction.transform.is_none() {
        if pressed(ctx, Modifiers::ALT, Key::A) {
            app.selection = Default::default();
        } else if pressed(ctx, Modifiers::NONE, Key::A) {
            app.select_all();
        }
        if pressed(ctx, Modifiers::SHIFT, Key::K) {
            app.set_key(Track::Cage);
        } else if pressed(ctx, Modifiers::NONE, Key::K) {
            app.set_key(Track::Skeleton);
        }
        if pressed(ctx, Modifiers::NONE, Key::Space) {
            app.toggle_play();
        }
        if pressed(ctx, Modifiers::NONE, Key::Delete) {
            app.delete_selected_key();
        }
        for (key, tool) in [
            (Key::W, Tool::Move),
            (Key::E, Tool::Rotate),
            (Key::T, Tool::Scale),
        ] {
            if pressed(ctx, Modifiers::NONE, key) {
                app.tool = tool;
            }
        }
    }
    crate::view_input::view_keys(app, ctx);
}
