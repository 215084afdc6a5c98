//! cagerig studio: the interactive editor where the skeleton and the cage of a character are
//! edited together, live, with every structure kept in sync by the library's `RigSession`.
//!
//! | module | concern |
//! |---|---|
//! | `rig_open` | opening a character (built-in demo, OBJ set, glTF, FBX) |
//! | `opening` | unsaved-edits question, background loading with progress, swapping documents |
//! | `document` | the rig session, its keys, one command path, gestures, undo / redo |
//! | `history` | undo / redo stacks of snapshots |
//! | `keys` | skeleton and cage keyframes, playback, the paper tool's animation files |
//! | `session_file` | the versioned `.cagerig` session file, autosave and recovery |
//! | `app` | application state, the frame, autosave |
//! | `scripted_run` | `--script`, `--screenshot`, `--quit-after-frames`, `--frame-stats` |
//! | `viewport` | a 3D view rendered by `cagerig-render` into its own textures |
//! | `view_input` | orbit / pan / zoom, picking, box selection, G / R / S keys |
//! | `picking` | projection, mouse rays, nearest visible point, occlusion |
//! | `gizmo` | gizmo maths (axis / plane / free drags, rings, trackball, scale) |
//! | `transform` | interactive grab / rotate / scale of the selection |
//! | `overlay` | selection, gizmo, names and warnings painted over a view |
//! | `timeline` | skeleton and cage tracks, play / loop / speed, scrubbing |
//! | `inspector` | layers, colour maps, skinning, locks, numeric entry |
//! | `menus` | menu bar and dialogs (open, save, export, recovery, shortcuts) |
//! | `status` | status bar and log panel |
//! | `shortcuts` | window-wide keyboard shortcuts |
//! | `export` | OBJ / JSON / animation / glTF export |
//! | `frame_stats` | per-frame timings for `--frame-stats` |
//! | `benchmark_drag` | simulated drags for frame-time benchmarks |

pub mod app;
pub mod benchmark_drag;
pub mod document;
pub mod export;
pub mod frame_stats;
pub mod gizmo;
pub mod history;
pub mod inspector;
pub mod keys;
pub mod menus;
pub mod opening;
pub mod overlay;
pub mod picking;
pub mod rig_open;
pub mod scripted_run;
pub mod session_file;
pub mod shortcuts;
pub mod status;
pub mod timeline;
pub mod transform;
pub mod view_input;
pub mod viewport;

pub use app::{StartupOptions, StudioApp};
