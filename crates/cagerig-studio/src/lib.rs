//! cagerig studio: the interactive editor where the skeleton and the cage of a character are
//! edited together, live, with every structure kept in sync by the library's `RigSession`.
//!
//! [`StudioApp`] owns the parts and runs the frame; every panel is given only the parts it
//! uses, and asks for more through [`action::Action`]s.
//!
//! | module | concern |
//! |---|---|
//! | **parts of the state** | |
//! | `document` (and `document_skeleton`, `history`, `keys`, `skeleton_draft`, `binding`, `offload`, `rig_open`, `unrigged`, `session_file`, `saved_binding`, `session_restore`) | the document model, from the GUI-free crate `cagerig-document`: the rig session, keys, skeleton building, undo, opening characters, session files |
//! | `project` | the document with its files: saving, autosave, export, animation import |
//! | `view_state` | the two views' cameras, layout, layers, colour map |
//! | `tools` | selection, tool, mouse state, numeric entry; a transform as one gesture |
//! | `selection` | selected cage vertices and joint, what a click selects, the tool |
//! | `timeline` | playhead and playback; the skeleton and cage tracks panel |
//! | `dialogs` | the dialogs' fields and windows (open, save, export, recovery, shortcuts) |
//! | `diagnostics` | the log and the frame timings |
//! | `action` | what menus, dialogs and shortcuts ask the application for |
//! | **the application** | |
//! | `app` | owns the parts, runs the frame, carries out actions |
//! | `open_document` | unsaved-edits question, background loading, swapping documents |
//! | `opening` | open requests, the background load and its progress window |
//! | `startup` | the startup options |
//! | `page_files` | the web edition's files: file input, samples, downloads |
//! | `scripted_run` | `--script`, `--screenshot`, `--quit-after-frames`, `--frame-stats` |
//! | **panels** | |
//! | `menus` | menu bar |
//! | `inspector` | layers, colour maps, skinning, locks, numeric entry |
//! | `skeleton_panel` | building the skeleton: add by clicking, mirror, list, rename, parent, Bind |
//! | `status` | status bar and log panel |
//! | `shortcuts` | window-wide keyboard shortcuts |
//! | `views` | the central panel: lays out, draws the two views |
//! | `view_mouse` | orbit / pan / zoom, picking and box selection, drags |
//! | `view_keys` | G / R / S keys, constraints and typed values, F |
//! | `overlay` | selection, gizmo, names and warnings painted over a view |
//! | **below the panels** | |
//! | `doc_commands` | a command as the panels run it: logged, timed |
//! | `viewport` | a 3D view rendered by `cagerig-render` into its own textures |
//! | `view_picking` | what the mouse hits in a view |
//! | `picking` | projection, mouse rays, nearest visible point, occlusion |
//! | `joint_placement` | a clicked joint goes to the middle of the body under the cursor |
//! | `gizmo` | gizmo maths (axis / plane / free drags, rings, trackball, scale) |
//! | `transform` | grab / rotate / scale of the selection: start, one step |
//! | `export` | OBJ / JSON / animation / glTF export |
//! | `frame_stats` | per-frame timings for `--frame-stats` |
//! | `benchmark_drag` | simulated drags for frame-time benchmarks |

pub mod action;
pub mod app;
pub mod benchmark_drag;
pub mod diagnostics;
pub mod dialogs;
pub mod doc_commands;
pub mod export;
pub mod frame_stats;
pub mod gizmo;
pub mod inspector;
pub mod joint_placement;
pub mod menus;
pub mod open_document;
pub mod opening;
pub mod overlay;
pub mod page_files;
pub mod picking;
pub mod project;
pub mod scripted_run;
pub mod selection;
pub mod shortcuts;
pub mod skeleton_panel;
pub mod startup;
pub mod status;
pub mod timeline;
pub mod tools;
pub mod transform;
pub mod view_keys;
pub mod view_mouse;
pub mod view_picking;
pub mod view_state;
pub mod viewport;
pub mod views;

// The document model lives in `cagerig-document` (no GUI dependencies, so that the fuzz
// targets build it); its modules keep their paths here.
pub use cagerig_document::{
    binding, document, document_skeleton, history, keys, offload, rig_open, saved_binding,
    session_file, session_restore, skeleton_draft, unrigged,
};

pub use app::StudioApp;
pub use startup::StartupOptions;
