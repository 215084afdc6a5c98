//! What the menus, the dialogs and the window's shortcuts ask the application for, when it
//! takes more than the part of the state they were given: opening, saving, undo, selection
//! of the whole cage, keys, the tool. The application carries them out in order right after
//! the panel that asked (see `StudioApp::apply`).

use std::path::PathBuf;

use cagerig_render::CameraPreset;

use crate::document::Command;
use crate::keys::Track;
use crate::opening::{AfterConfirm, OpenRequest};
use crate::selection::Tool;

/// A request of a menu, a dialog or a shortcut.
#[derive(Debug, Clone, PartialEq)]
pub enum Action {
    /// Opens a path by its extension (a session or a character), asking about unsaved edits.
    OpenPath(PathBuf),
    /// Opens something in place of the document, asking about unsaved edits.
    RequestOpen(OpenRequest),
    /// Opens something now, without asking (the recovery offered at start).
    StartOpen(OpenRequest),
    /// Saves to the session's file, or asks for one.
    Save,
    /// Saves to the path typed in the Save-as dialog (kept open if that fails), then does
    /// what waited for the save.
    SaveAs(String),
    /// The unsaved-edits question was answered Save: save, then go on.
    SaveThenContinue(AfterConfirm),
    /// The unsaved-edits question was answered Don't save: go on.
    Continue(AfterConfirm),
    /// Deletes the recovery file offered at start.
    DiscardRecovery,
    /// Exports everything into a folder.
    Export(PathBuf),
    /// Replaces a track's keys with an animation file.
    ImportAnimation(Track, PathBuf),
    /// Puts animation `i` of the character on the skeleton track.
    LoadCharacterAnimation(usize),
    Quit,
    /// The web edition: choose a character with the page's file input.
    ChooseCharacter,
    /// The web edition: open a sample the page serves (its file name).
    OpenSample(String),
    /// The web edition: download the rig as a `.glb`.
    DownloadGlb,
    Undo,
    Redo,
    /// Selects every cage vertex.
    SelectAll,
    SelectNone,
    /// Runs a command of the document (one undo step).
    Run(Command),
    /// Frames the rig in both views, from a preset direction or the current one.
    FrameViews(Option<CameraPreset>),
    /// Keys the current pose or the rest cage at the playhead.
    SetKey(Track),
    DeleteSelectedKey,
    TogglePlay,
    SetTool(Tool),
}
