//! cagerig studio: the interactive editor where the skeleton and the cage of a character are
//! edited together, live, with every structure kept in sync by the library's `RigSession`.
//!
//! [`StudioApp`] owns the parts and runs the frame; every panel is given only the parts it
//! uses, and asks for more through [`action::Action`]s.
//!
//! | module | concern |
//! |---|---|
//! | **parts of the state** | |
//! | `document` | the rig session, its keys, one command path, gestures, undo / redo |
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
//! | `history` | undo / redo stacks of snapshots |
//! | `document_skeleton` | skeleton building: draft edits, shown skeletons, Bind as one undo step |
//! | `skeleton_draft` | the skeleton being built: add, move, re-parent, rename, delete, X mirror |
//! | `binding` | Bind: automatic or carried weights and the new session, on a background thread |
//! | `keys` | skeleton and cage keyframes, playback, the paper tool's animation files |
//! | `session_file` | the versioned `.cagerig` session file, autosave and recovery |
//! | `saved_binding` | a skeleton and weights bound in the studio, as a session file keeps them |
//! | `rig_open` | opening a character (built-in demo, OBJ set, glTF, FBX) |
//! | `unrigged` | opening a mesh with no skeleton: its cage and a placeholder rig |
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
pub mod binding;
pub mod diagnostics;
pub mod dialogs;
pub mod doc_commands;
pub mod document;
pub mod document_skeleton;
pub mod export;
pub mod frame_stats;
pub mod gizmo;
pub mod history;
pub mod inspector;
pub mod joint_placement;
pub mod keys;
pub mod menus;
pub mod open_document;
pub mod opening;
pub mod overlay;
pub mod picking;
pub mod project;
pub mod rig_open;
pub mod saved_binding;
pub mod scripted_run;
pub mod selection;
pub mod session_file;
pub mod shortcuts;
pub mod skeleton_draft;
pub mod skeleton_panel;
pub mod startup;
pub mod status;
pub mod timeline;
pub mod tools;
pub mod transform;
pub mod unrigged;
pub mod view_keys;
pub mod view_mouse;
pub mod view_picking;
pub mod view_state;
pub mod viewport;
pub mod views;

pub use app::StudioApp;
pub use startup::StartupOptions;
