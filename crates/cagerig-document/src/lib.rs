//! The cagerig editor's document, without a GUI: what `cagerig-studio` edits, saves and
//! reopens, in a crate that a fuzz target or a headless tool can build without egui, wgpu or
//! winit.
//!
//! | module | concern |
//! |---|---|
//! | `document` | the rig session, its keys, one command path, gestures, undo / redo |
//! | `document_skeleton` | skeleton building: draft edits, shown skeletons, Bind as one undo step |
//! | `history` | undo / redo stacks of snapshots |
//! | `skeleton_draft` | the skeleton being built: add, move, re-parent, rename, delete, X mirror |
//! | `binding` | Bind: automatic or carried weights and the new session, on a background thread |
//! | `offload` | a bind's automatic weights computed elsewhere (the web page's worker), and their encoding |
//! | `keys` | skeleton and cage keyframes, playback, the paper tool's animation files |
//! | `rig_open` | opening a character (built-in demo, OBJ set, glTF, FBX) |
//! | `unrigged` | opening a mesh with no skeleton: its cage and a placeholder rig |
//! | `session_file` | the versioned `.cagerig` session file, autosave and recovery |
//! | `saved_binding` | a skeleton and weights bound in the studio, as a session file keeps them |
//! | `session_restore` | a parsed session file restored onto its opened rig, every part checked |

mod bind_progress;
pub mod binding;
pub mod document;
pub mod document_skeleton;
pub mod history;
pub mod keys;
pub mod offload;
pub mod rig_open;
pub mod saved_binding;
pub mod session_file;
pub mod session_restore;
pub mod skeleton_draft;
pub mod unrigged;
