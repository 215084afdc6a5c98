//! How the studio starts: what to open, the scripted-run options of the command line, and
//! where startup failures are reported for the binary's exit status.

use std::path::PathBuf;
use std::sync::Arc;

use crate::benchmark_drag::DragBenchmark;
use crate::rig_open::RigSource;
use crate::view_state::ColorMode;

/// How the studio starts (the command line, or a test).
#[derive(Debug, Clone, Default)]
pub struct StartupOptions {
    /// What to open (`None`: the built-in demo, unless `session` is given).
    pub source: Option<RigSource>,
    /// A `.cagerig` session to open.
    pub session: Option<PathBuf>,
    /// An edit script (`cagerig edit`'s JSON) applied through the editor before the first frame.
    pub script: Option<PathBuf>,
    /// Save the session here after the script.
    pub save_session: Option<PathBuf>,
    /// Write a screenshot of the window here, then quit.
    pub screenshot: Option<PathBuf>,
    /// Quit after this many frames.
    pub quit_after_frames: Option<u64>,
    /// Write per-frame timings here when quitting.
    pub frame_stats: Option<PathBuf>,
    /// State directory (recovery file, recent files); `None`: the default.
    pub state_dir: Option<PathBuf>,
    /// Simulate a drag for every frame (benchmarks of the frame time).
    pub drag_benchmark: Option<DragBenchmark>,
    /// Cage vertices selected at start (figures of scripted runs).
    pub select_cage: Vec<usize>,
    /// Joint selected at start.
    pub select_joint: Option<usize>,
    /// Colour map at start.
    pub color_mode: ColorMode,
    /// Cage coordinates to bind with after opening (`--coords`); `None`: as opened.
    pub coords: Option<cagerig::CoordsKind>,
    /// The web page's files (file input, samples, downloads); `None` in the native studio.
    pub page_files: Option<crate::page_files::SharedPageFiles>,
    /// What computes a Bind's automatic weights (the web page's worker); `None`: the bind's
    /// own background thread, as in the native studio.
    pub weights_offload: Option<std::sync::Arc<dyn crate::offload::WeightsOffload>>,
    /// Failures of the startup actions (open, script, save), for the binary's exit status.
    pub failures: Arc<std::sync::Mutex<Vec<String>>>,
}
