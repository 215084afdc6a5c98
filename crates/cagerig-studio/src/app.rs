//! The studio's application state and its frame: panels around two 3D views, and autosave
//! (opening is in `opening`, scripted runs in `scripted_run`).

use std::collections::BTreeSet;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::{Duration, Instant};

use cagerig_render::Renderer;
use cagerig_render::rig_scene::{ColorBy, Layers, Pose};

use crate::document::Document;
use crate::frame_stats::FrameStats;
use crate::opening::{AfterConfirm, OpenRequest, PendingOpen};
use crate::rig_open::RigSource;
use crate::session_file::{SessionFile, StateDir, default_state_dir};
use crate::timeline::TimelineState;
use crate::view_input::Interaction;
use crate::viewport::View;

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
    pub drag_benchmark: Option<crate::benchmark_drag::DragBenchmark>,
    /// Cage vertices selected at start (figures of scripted runs).
    pub select_cage: Vec<usize>,
    /// Joint selected at start.
    pub select_joint: Option<usize>,
    /// Colour map at start.
    pub color_mode: ColorMode,
    /// Failures of the startup actions (open, script, save), for the binary's exit status.
    pub failures: Arc<std::sync::Mutex<Vec<String>>>,
}

/// Which colour map the views show.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, clap::ValueEnum)]
pub enum ColorMode {
    #[default]
    None,
    /// Ω of the selected joint.
    Weights,
    /// Φ of the selected cage vertex.
    CageCoords,
    /// Ψ of the selected joint.
    JointCoords,
}

/// Selected cage vertices and joint (the same indices in both poses).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Selection {
    pub cage: BTreeSet<usize>,
    pub joint: Option<usize>,
    /// Whether the gizmo and the keys act on the joint (last clicked) rather than the cage.
    pub joint_is_active: bool,
}

impl Selection {
    pub fn is_empty(&self) -> bool {
        self.cage.is_empty() && self.joint.is_none()
    }

    /// Whether transforms act on the selected joint.
    pub fn joint_active(&self) -> bool {
        self.joint.is_some() && (self.joint_is_active || self.cage.is_empty())
    }
}

/// How the two views share the window.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Layout {
    Split,
    CurrentOnly,
    RestOnly,
}

/// The active transform tool of the gizmo.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tool {
    Move,
    Rotate,
    Scale,
}

/// A line of the log panel.
#[derive(Debug, Clone)]
pub struct LogLine {
    pub level: LogLevel,
    pub text: String,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LogLevel {
    Info,
    Warning,
    Error,
}

/// Text fields of the dialogs.
#[derive(Debug, Clone, Default)]
pub struct Dialogs {
    pub open: Option<String>,
    pub save_as: Option<String>,
    pub export_dir: Option<String>,
    pub import_animation: Option<(crate::keys::Track, String)>,
    pub export_animation: Option<String>,
    pub help: bool,
    /// A recovery file offered at start.
    pub recovery: Option<PathBuf>,
    /// File > Open: generate a cage (of `cage_vertices` vertices) when the character has none.
    pub generate_cage: bool,
    pub cage_vertices: usize,
    /// Unsaved edits would be lost (by closing, or by opening something else): Save / Don't
    /// save / Cancel, then this.
    pub confirm: Option<AfterConfirm>,
    /// What to do once the Save-as dialog has saved (Save chosen without a session path).
    pub after_save: Option<AfterConfirm>,
}

/// The editor.
pub struct StudioApp {
    pub doc: Option<Document>,
    pub views: [View; 2],
    pub layout: Layout,
    pub layers: Layers,
    pub color_mode: ColorMode,
    pub selection: Selection,
    pub tool: Tool,
    pub interaction: Interaction,
    pub timeline: TimelineState,
    pub log: Vec<LogLine>,
    pub dialogs: Dialogs,
    pub state_dir: StateDir,
    /// Where the session was last saved or opened from.
    pub session_path: Option<PathBuf>,
    /// `doc.edits` when last saved / autosaved.
    pub saved_edits: u64,
    /// The user saved or discarded the edits in the close dialog: the window may close.
    pub close_approved: bool,
    autosaved_edits: u64,
    last_autosave: Instant,
    renderer: Option<Arc<Renderer>>,
    pub stats: FrameStats,
    pub(crate) options: StartupOptions,
    pub(crate) frames: u64,
    pub(crate) screenshot_requested: bool,
    pub(crate) screenshot_done: bool,
    /// Where the screenshot callback puts the window's pixels.
    pub(crate) screenshot_slot: Arc<std::sync::Mutex<Option<Arc<egui::ColorImage>>>>,
    pub render_error: Option<String>,
    pub quit_requested: bool,
    pub numeric: crate::inspector::NumericEntry,
    /// Animations of the open glTF / FBX character (File > Load animation).
    pub animations: Vec<cagerig_formats::ImportedAnimation>,
    /// Their morph targets (played as cage keys, see `load_character_animation`).
    pub morph_targets: cagerig_formats::MorphTargets,
    /// A rig loading in the background.
    pub(crate) pending_open: Option<PendingOpen>,
}

/// Index of the current-pose view in [`StudioApp::views`].
pub const CURRENT: usize = 0;
/// Index of the rest-pose view.
pub const REST: usize = 1;

impl StudioApp {
    /// Builds the app: opens the rig or session, runs the script, saves the session if asked.
    /// Problems are logged (and shown), never fatal: the studio opens on what it could load.
    pub fn new(cc: &eframe::CreationContext<'_>, options: StartupOptions) -> Self {
        let renderer = cc
            .wgpu_render_state
            .as_ref()
            .map(|rs| Arc::new(Renderer::new(&rs.device)));
        let state_dir = StateDir::new(options.state_dir.clone().unwrap_or_else(default_state_dir));
        let mut app = Self {
            doc: None,
            views: [View::new(Pose::Current), View::new(Pose::Rest)],
            layout: Layout::Split,
            layers: Layers::default(),
            color_mode: ColorMode::None,
            selection: Selection::default(),
            tool: Tool::Move,
            interaction: Interaction::default(),
            timeline: TimelineState::default(),
            log: Vec::new(),
            dialogs: Dialogs::default(),
            state_dir,
            session_path: None,
            saved_edits: 0,
            close_approved: false,
            autosaved_edits: 0,
            last_autosave: Instant::now(),
            renderer,
            stats: FrameStats::default(),
            options: options.clone(),
            frames: 0,
            screenshot_requested: false,
            screenshot_done: false,
            screenshot_slot: Arc::default(),
            render_error: None,
            quit_requested: false,
            numeric: Default::default(),
            animations: Vec::new(),
            morph_targets: Default::default(),
            pending_open: None,
        };
        if app.renderer.is_none() {
            app.log_error(
                "no wgpu device: the 3D views cannot be drawn (start with a wgpu renderer)",
            );
        }
        let scripted = options.script.is_some() || options.screenshot.is_some();
        if !scripted && options.session.is_none() {
            app.dialogs.recovery = app.state_dir.pending_recovery();
        }
        match (&options.session, &options.source) {
            (Some(path), _) => app.open_blocking(OpenRequest::Session(path.clone())),
            (None, source) => {
                app.open_blocking(OpenRequest::Rig(source.clone().unwrap_or_default()))
            }
        }
        if let Some(doc) = &app.doc {
            let (nc, nj) = (doc.session.rest_cage().len(), doc.session.skeleton().len());
            if let Some(k) = options.select_cage.iter().find(|&&k| k >= nc) {
                app.log_error(format!(
                    "--select-cage: cage vertex {k} does not exist (the cage has {nc} vertices)"
                ));
            } else {
                app.selection.cage = options.select_cage.iter().copied().collect();
            }
            match options.select_joint {
                Some(j) if j >= nj => app.log_error(format!(
                    "--select-joint: joint {j} does not exist (the rig has {nj} joints)"
                )),
                Some(j) => {
                    app.selection.joint = Some(j);
                    app.selection.joint_is_active = options.select_cage.is_empty();
                }
                None => {}
            }
        }
        app.color_mode = options.color_mode;
        let errors_before = app.error_count();
        if let Some(script) = &options.script {
            app.run_script_file(script);
        }
        if let Some(path) = &options.save_session {
            app.save_session_to(path);
        }
        let failed: Vec<String> = app
            .log
            .iter()
            .filter(|l| l.level == LogLevel::Error)
            .skip(errors_before)
            .map(|l| l.text.clone())
            .collect();
        let open_failed = app.doc.is_none()
            || (options.source.is_some() || options.session.is_some()) && errors_before > 0;
        if let Ok(mut f) = options.failures.lock() {
            if open_failed {
                f.extend(
                    app.log
                        .iter()
                        .filter(|l| l.level == LogLevel::Error)
                        .map(|l| l.text.clone()),
                );
            } else {
                f.extend(failed);
            }
        }
        app
    }

    /// Errors logged so far.
    pub fn error_count(&self) -> usize {
        self.log
            .iter()
            .filter(|l| l.level == LogLevel::Error)
            .count()
    }

    pub fn log_info(&mut self, text: impl Into<String>) {
        self.log.push(LogLine {
            level: LogLevel::Info,
            text: text.into(),
        });
    }

    pub fn log_warning(&mut self, text: impl Into<String>) {
        self.log.push(LogLine {
            level: LogLevel::Warning,
            text: text.into(),
        });
    }

    pub fn log_error(&mut self, text: impl Into<String>) {
        let text = text.into();
        eprintln!("cagerig-studio: {text}");
        self.log.push(LogLine {
            level: LogLevel::Error,
            text,
        });
    }

    pub(crate) fn set_document(&mut self, doc: Document) {
        self.doc = Some(doc);
        self.animations.clear();
        self.morph_targets = Default::default();
        self.selection = Selection::default();
        self.interaction = Interaction::default();
        self.timeline = TimelineState::default();
        for v in &mut self.views {
            v.framed = false;
        }
        self.saved_edits = 0;
        self.autosaved_edits = 0;
    }

    /// Saves the session to `path` (atomically).
    pub fn save_session_to(&mut self, path: &std::path::Path) -> bool {
        let Some(doc) = &self.doc else {
            self.log_error("nothing to save: no rig is open");
            return false;
        };
        let mut file = SessionFile::new(doc.source.clone(), doc.snapshot(), self.timeline.time);
        if self.views.iter().all(|v| v.framed) {
            file.cameras = Some([
                crate::viewport::camera_key(&self.views[CURRENT].camera),
                crate::viewport::camera_key(&self.views[REST].camera),
            ]);
        }
        let edits = doc.edits;
        match file.write(path) {
            Ok(()) => {
                self.saved_edits = edits;
                self.session_path = Some(path.to_path_buf());
                self.state_dir.add_recent(path);
                self.log_info(format!("saved session {}", path.display()));
                true
            }
            Err(e) => {
                self.log_error(e.to_string());
                false
            }
        }
    }

    /// The autosave is up to date with the document (e.g. just opened from a session file).
    pub(crate) fn mark_autosaved(&mut self) {
        self.autosaved_edits = self.saved_edits;
    }

    /// Whether the document has edits not saved in a session file.
    pub fn unsaved(&self) -> bool {
        self.doc
            .as_ref()
            .is_some_and(|d| d.edits != self.saved_edits)
    }

    /// Writes the recovery file now (true when written).
    pub fn autosave_now(&mut self) -> bool {
        let Some(doc) = &self.doc else { return false };
        let file = SessionFile::new(doc.source.clone(), doc.snapshot(), self.timeline.time);
        let edits = doc.edits;
        self.last_autosave = Instant::now();
        match self.state_dir.write_recovery(&file) {
            Ok(()) => {
                self.autosaved_edits = edits;
                true
            }
            Err(e) => {
                self.log_error(format!("autosave failed: {e}"));
                false
            }
        }
    }

    /// Autosave to the recovery file, at most every two seconds, after edits.
    fn autosave(&mut self) {
        let Some(doc) = &self.doc else { return };
        if self.options.screenshot.is_some() || self.options.script.is_some() {
            return;
        }
        if doc.edits == self.autosaved_edits
            || doc.in_gesture()
            || self.last_autosave.elapsed() < Duration::from_secs(2)
        {
            return;
        }
        self.autosave_now();
    }

    /// The colour map of the current selection.
    pub fn color_by(&self) -> ColorBy {
        match self.color_mode {
            ColorMode::None => ColorBy::None,
            ColorMode::Weights => self
                .selection
                .joint
                .map_or(ColorBy::None, ColorBy::JointWeights),
            ColorMode::JointCoords => self
                .selection
                .joint
                .map_or(ColorBy::None, ColorBy::JointCageCoords),
            ColorMode::CageCoords => self
                .selection
                .cage
                .first()
                .map_or(ColorBy::None, |&k| ColorBy::CageCoords(k)),
        }
    }

    pub fn renderer(&self) -> Option<&Arc<Renderer>> {
        self.renderer.as_ref()
    }

    /// Frames counted so far.
    pub fn frames(&self) -> u64 {
        self.frames
    }

    /// The startup options (for the drag benchmark).
    pub fn startup_options(&self) -> &StartupOptions {
        &self.options
    }
}

impl eframe::App for StudioApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let frame_start = Instant::now();
        let ctx = ui.ctx().clone();
        self.stats.begin_frame();
        self.poll_open(&ctx);
        self.handle_dropped_files(&ctx);
        self.hold_close_with_unsaved_edits(&ctx);
        crate::shortcuts::global_shortcuts(self, &ctx);
        crate::benchmark_drag::step(self);
        self.advance_playback(&ctx);
        crate::menus::menu_bar_ui(self, ui);
        crate::status::status_bar_ui(self, ui);
        crate::timeline::timeline_ui(self, ui);
        crate::inspector::inspector_ui(self, ui);
        let render_state = frame.wgpu_render_state().cloned();
        crate::view_input::views_ui(self, ui, render_state.as_ref());
        crate::menus::dialogs_ui(self, &ctx);
        crate::opening::opening_ui(self, &ctx);
        self.autosave();
        let title = match &self.doc {
            Some(d) => format!(
                "cagerig studio — {}{}",
                self.session_path
                    .as_ref()
                    .map_or_else(|| d.source.display_name(), |p| p.display().to_string()),
                if self.unsaved() { " •" } else { "" }
            ),
            None => "cagerig studio".into(),
        };
        ctx.send_viewport_cmd(egui::ViewportCommand::Title(title));
        self.stats
            .end_frame(frame_start.elapsed().as_secs_f64() * 1e3);
        self.scripted_frame_end(&ctx);
    }

    fn on_exit(&mut self) {
        self.write_frame_stats();
        // A clean exit: the recovery file is not needed (unsaved edits were asked about).
        if !self.unsaved() || self.close_approved {
            self.state_dir.clear_recovery();
        }
    }
}

impl StudioApp {
    /// A request to close the window while edits are unsaved is held back and asked about
    /// (scripted runs close without asking).
    fn hold_close_with_unsaved_edits(&mut self, ctx: &egui::Context) {
        let scripted =
            self.options.screenshot.is_some() || self.options.quit_after_frames.is_some();
        if ctx.input(|i| i.viewport().close_requested())
            && self.unsaved()
            && !self.close_approved
            && !scripted
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.dialogs.confirm = Some(AfterConfirm::Close);
        }
    }

    /// Lets the window close (after the close dialog saved or discarded the edits).
    pub fn approve_close(&mut self, ctx: &egui::Context) {
        self.close_approved = true;
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }

    fn handle_dropped_files(&mut self, ctx: &egui::Context) {
        let dropped: Vec<PathBuf> = ctx.input(|i| {
            i.raw
                .dropped_files
                .iter()
                .map(|f| f.path().to_path_buf())
                .collect()
        });
        for path in dropped {
            self.open_path(&path);
        }
    }

    fn advance_playback(&mut self, ctx: &egui::Context) {
        if !self.timeline.playing {
            return;
        }
        let dt = f64::from(ctx.input(|i| i.stable_dt)).min(0.1);
        let Some(doc) = &mut self.doc else { return };
        let duration = doc.keys.duration();
        let mut t = self.timeline.time + dt * self.timeline.speed;
        if t > duration {
            if self.timeline.looping && duration > 0.0 {
                t = t.rem_euclid(duration);
            } else {
                t = duration;
                self.timeline.playing = false;
            }
        }
        self.timeline.time = t;
        match doc.sample(t) {
            Ok(_) => self.stats.sync_ms = doc.last_sync_ms,
            Err(e) => {
                self.timeline.playing = false;
                self.log_error(format!("playback: {e}"));
            }
        }
        ctx.request_repaint();
    }
}
