//! The studio: the owner of its parts — the document with its files ([`Project`]), the views
//! ([`ViewState`]), interaction ([`Tools`]), the timeline, the dialogs and the diagnostics —
//! and its frame, which hands each panel the parts it uses and carries out the [`Action`]s
//! the menus, dialogs and shortcuts return. Opening documents is in `open_document`.

use std::path::{Path, PathBuf};
use std::sync::Arc;
use web_time::Instant;

use cagerig_render::{CameraPreset, Renderer};
use glam::DVec3;

use crate::action::Action;
use crate::diagnostics::Diagnostics;
use crate::dialogs::{Dialogs, dialogs_ui};
use crate::doc_commands::run_command;
use crate::document::Command;
use crate::inspector::inspector_ui;
use crate::menus::menu_bar_ui;
use crate::opening::{AfterConfirm, OpenRequest, PendingOpen, opening_ui};
use crate::project::Project;
use crate::rig_open::RigSource;
use crate::scripted_run::{ScriptedRun, run_script_file};
use crate::session_file::{StateDir, default_state_dir};
use crate::startup::StartupOptions;
use crate::status::status_bar_ui;
use crate::timeline::{TimelineState, timeline_ui};
use crate::tools::Tools;
use crate::view_keys::view_keys;
use crate::view_state::{REST, ViewState};
use crate::views::{Gpu, views_ui};

/// The editor.
pub struct StudioApp {
    /// The document (rig session, keys, history) and its files.
    pub project: Project,
    /// The views: cameras, layout, layers, colour map.
    pub view: ViewState,
    /// Selection, tool, mouse state, numeric entry.
    pub tools: Tools,
    /// Playhead, playback, key selection.
    pub timeline: TimelineState,
    pub dialogs: Dialogs,
    /// The log and the frame timings.
    pub diagnostics: Diagnostics,
    renderer: Option<Arc<Renderer>>,
    pub(crate) run: ScriptedRun,
    quit_requested: bool,
    /// A rig loading in the background.
    pub(crate) pending_open: Option<PendingOpen>,
}

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
            project: Project::new(state_dir),
            view: ViewState::default(),
            tools: Tools::default(),
            timeline: TimelineState::default(),
            dialogs: Dialogs::default(),
            diagnostics: Diagnostics::default(),
            renderer,
            run: ScriptedRun::new(options.clone()),
            quit_requested: false,
            pending_open: None,
        };
        if app.renderer.is_none() {
            app.diagnostics
                .log
                .error("no wgpu device: the 3D views cannot be drawn (start with a wgpu renderer)");
        }
        let scripted = options.script.is_some() || options.screenshot.is_some();
        if !scripted && options.session.is_none() && options.page_files.is_none() {
            app.dialogs.recovery = app.project.state_dir.pending_recovery();
        }
        match (&options.session, &options.source) {
            (Some(path), _) => app.open_blocking(OpenRequest::Session(path.clone())),
            (None, source) => {
                app.open_blocking(OpenRequest::Rig(source.clone().unwrap_or_default()))
            }
        }
        if let (Some(kind), Some(doc)) = (options.coords, app.project.doc.as_mut())
            && doc.session.coords_kind() != kind
            && let Err(e) = doc.execute(&crate::document::Command::SetCoords(kind))
        {
            app.diagnostics.log.error(format!("--coords {kind}: {e}"));
        }
        app.select_at_start(&options);
        app.view.color_mode = options.color_mode;
        let errors_before = app.diagnostics.log.error_count();
        if let Some(script) = &options.script {
            run_script_file(app.project.doc.as_mut(), script, &mut app.diagnostics.log);
        }
        if let Some(path) = &options.save_session {
            app.save_session_to(path);
        }
        let errors = app.diagnostics.log.errors();
        let failed: Vec<String> = errors.skip(errors_before).map(str::to_owned).collect();
        let open_failed = app.project.doc.is_none()
            || (options.source.is_some() || options.session.is_some()) && errors_before > 0;
        if let Ok(mut f) = options.failures.lock() {
            if open_failed {
                f.extend(app.diagnostics.log.errors().map(str::to_owned));
            } else {
                f.extend(failed);
            }
        }
        app
    }

    /// `--select-cage` and `--select-joint` (an index that does not exist is an error).
    fn select_at_start(&mut self, options: &StartupOptions) {
        let Some(doc) = &self.project.doc else { return };
        let log = &mut self.diagnostics.log;
        let selection = &mut self.tools.selection;
        let (nc, nj) = (doc.session.rest_cage().len(), doc.session.skeleton().len());
        if let Some(k) = options.select_cage.iter().find(|&&k| k >= nc) {
            log.error(format!(
                "--select-cage: cage vertex {k} does not exist (the cage has {nc} vertices)"
            ));
        } else {
            selection.cage = options.select_cage.iter().copied().collect();
        }
        match options.select_joint {
            Some(j) if j >= nj => log.error(format!(
                "--select-joint: joint {j} does not exist (the rig has {nj} joints)"
            )),
            Some(j) => {
                selection.joint = Some(j);
                selection.joint_is_active = options.select_cage.is_empty();
            }
            None => {}
        }
    }

    /// Carries out `action` (asked for by a menu, a dialog or a shortcut).
    pub fn apply(&mut self, action: Action, ctx: &egui::Context) {
        match action {
            Action::OpenPath(path) => self.open_path(&path),
            Action::RequestOpen(request) => self.request_open(request),
            Action::StartOpen(request) => self.start_open(request),
            Action::Save => self.save(),
            Action::SaveAs(typed) => {
                if !self.save_session_to(Path::new(typed.trim())) {
                    self.dialogs.save_as = Some(typed);
                } else if let Some(after) = self.dialogs.after_save.take() {
                    self.continue_after_confirm(ctx, after);
                }
            }
            Action::SaveThenContinue(after) => self.save_then_continue(ctx, after),
            Action::Continue(after) => self.continue_after_confirm(ctx, after),
            Action::DiscardRecovery => self.project.state_dir.clear_recovery(),
            Action::Export(dir) => self.project.export_to(&dir, &mut self.diagnostics.log),
            Action::ImportAnimation(track, path) => {
                let log = &mut self.diagnostics.log;
                self.project.import_animation(track, &path, log);
            }
            Action::LoadCharacterAnimation(index) => self.load_character_animation(index),
            Action::Quit => self.quit_requested = true,
            Action::ChooseCharacter => {
                if let Some(page) = &self.run.options().page_files {
                    page.choose_character();
                }
            }
            Action::OpenSample(name) => {
                if let Some(page) = &self.run.options().page_files {
                    page.fetch_sample(&name);
                }
            }
            Action::DownloadGlb => self.download_glb(),
            Action::Undo => self.undo(),
            Action::Redo => self.redo(),
            Action::SelectAll => self.select_all(),
            Action::SelectNone => self.tools.selection = Default::default(),
            Action::Run(command) => {
                self.run_command(&command);
            }
            Action::FrameViews(preset) => self.frame_views(preset),
            Action::SetKey(track) => {
                let doc = self.project.doc.as_mut();
                self.timeline.set_key(track, doc, &mut self.diagnostics);
            }
            Action::DeleteSelectedKey => {
                let doc = self.project.doc.as_mut();
                self.timeline
                    .delete_selected_key(doc, &mut self.diagnostics);
            }
            Action::TogglePlay => {
                let doc = self.project.doc.as_ref();
                self.timeline.toggle_play(doc, &mut self.diagnostics);
            }
            Action::SetTool(tool) => self.tools.tool = tool,
        }
    }

    fn apply_all(&mut self, actions: Vec<Action>, ctx: &egui::Context) {
        for action in actions {
            self.apply(action, ctx);
        }
    }

    /// Runs a command as one undo step, logging a failure.
    pub fn run_command(&mut self, command: &Command) -> bool {
        let Some(doc) = &mut self.project.doc else {
            return false;
        };
        run_command(doc, command, &mut self.diagnostics)
    }

    /// Undo (a transform in progress is cancelled first).
    pub fn undo(&mut self) {
        let log = &mut self.diagnostics.log;
        self.tools.cancel_transform(self.project.doc.as_mut(), log);
        self.project.undo(log);
    }

    /// Redo (a transform in progress is cancelled first).
    pub fn redo(&mut self) {
        let log = &mut self.diagnostics.log;
        self.tools.cancel_transform(self.project.doc.as_mut(), log);
        self.project.redo(log);
    }

    /// Selects every cage vertex.
    pub fn select_all(&mut self) {
        if let Some(doc) = &self.project.doc {
            let cage_len = doc.session.rest_cage().len();
            self.tools.selection.select_all_cage(cage_len);
        }
    }

    /// Frames the rig in both views, from `preset` (or the current angles).
    pub fn frame_views(&mut self, preset: Option<CameraPreset>) {
        if let Some(doc) = &self.project.doc {
            self.view.frame_views(&doc.session, preset);
        }
    }

    /// Moves the playhead and samples the keys there.
    pub fn scrub_to(&mut self, time: f64) {
        let doc = self.project.doc.as_mut();
        self.timeline.scrub_to(time, doc, &mut self.diagnostics);
    }

    /// Puts animation `index` of the glTF / FBX character on the skeleton track (one undo
    /// step), the playhead at 0.
    pub fn load_character_animation(&mut self, index: usize) {
        if self
            .project
            .load_character_animation(index, &mut self.diagnostics.log)
        {
            self.timeline.time = 0.0;
        }
    }

    /// Saves to the session's file, or asks for one (the web edition downloads it).
    pub fn save(&mut self) {
        if self.run.options().page_files.is_some() {
            self.download_session();
            return;
        }
        match self.project.session_path.clone() {
            Some(p) => {
                self.save_session_to(&p);
            }
            None => self.dialogs.ask_save_as(),
        }
    }

    /// The unsaved-edits question was answered Save: saves to the session's file and goes on,
    /// or asks for a file and goes on once saved there.
    fn save_then_continue(&mut self, ctx: &egui::Context, after: AfterConfirm) {
        if self.run.options().page_files.is_some() {
            if self.download_session() {
                self.continue_after_confirm(ctx, after);
            }
            return;
        }
        match self.project.session_path.clone() {
            Some(path) => {
                if self.save_session_to(&path) {
                    self.continue_after_confirm(ctx, after);
                }
            }
            None => {
                self.dialogs.ask_save_as();
                self.dialogs.after_save = Some(after);
            }
        }
    }

    /// Saves the session to `path` (atomically), with the playhead and the cameras.
    pub fn save_session_to(&mut self, path: &Path) -> bool {
        let cameras = self.view.camera_keys();
        let log = &mut self.diagnostics.log;
        self.project.save_to(path, self.timeline.time, cameras, log)
    }

    /// The web edition: offers the session as a download (`<character>.cagerig`), with the
    /// playhead and the cameras; true when the page took it.
    pub fn download_session(&mut self) -> bool {
        let Some(page) = self.run.options().page_files.clone() else {
            return false;
        };
        let cameras = self.view.camera_keys();
        let log = &mut self.diagnostics.log;
        let Some((name, text)) = self.project.session_text(self.timeline.time, cameras, log) else {
            return false;
        };
        match page.download(&name, "application/json", text.as_bytes()) {
            Ok(()) => {
                self.project.mark_saved();
                log.info(format!("session downloaded as {name}"));
                true
            }
            Err(e) => {
                log.error(format!("{name}: the download failed: {e}"));
                false
            }
        }
    }

    /// The web edition: offers the rig as a glTF download (under DQS, CoR or the blended
    /// method with the current skin baked in, as File ▸ Export writes it).
    pub fn download_glb(&mut self) {
        let Some(page) = self.run.options().page_files.clone() else {
            return;
        };
        let log = &mut self.diagnostics.log;
        let Some(doc) = &self.project.doc else {
            log.error("nothing to export: no rig is open");
            return;
        };
        let name = crate::project::file_stem_of(&doc.source);
        match cagerig_formats::export_character_baked_glb(&doc.session, &name) {
            Ok((bytes, _)) => {
                match page.download(&format!("{name}.glb"), "model/gltf-binary", &bytes) {
                    Ok(()) => log.info(format!("{name}.glb downloaded ({} bytes)", bytes.len())),
                    Err(e) => log.error(format!("{name}.glb: the download failed: {e}")),
                }
            }
            Err(e) => log.error(format!("glTF export: {e}")),
        }
    }

    /// Opens a character file whose bytes the page read (its file input, a dropped file or a
    /// sample), named `name` (`.glb`, `.gltf`), asking about unsaved edits first. A file without
    /// a cage opens with `generated_cage` when the page made it beforehand
    /// ([`crate::rig_open::generated_cage_of`], in a worker), else with one generated now.
    pub fn open_character_bytes(
        &mut self,
        name: &str,
        bytes: Vec<u8>,
        generated_cage: Option<cagerig::cage_gen::GeneratedCage>,
    ) {
        self.request_open(OpenRequest::Rig(RigSource::Memory {
            path: PathBuf::from(name),
            bytes: bytes.into(),
            auto_cage: None,
            generated_cage: generated_cage.map(Arc::new),
        }));
    }

    /// Writes the recovery file now (true when written).
    pub fn autosave_now(&mut self) -> bool {
        let log = &mut self.diagnostics.log;
        self.project.autosave_now(self.timeline.time, log)
    }

    /// Whether the document has edits not saved in a session file.
    pub fn unsaved(&self) -> bool {
        self.project.unsaved()
    }

    /// Where the gizmo of the active selection sits in `view`, and which handles it shows.
    pub fn gizmo_pivot(&self, view: usize) -> Option<(DVec3, bool, bool)> {
        let doc = self.project.doc.as_ref()?;
        self.tools
            .gizmo_pivot(&doc.session, &doc.shown_skeleton(view == REST), view)
    }

    pub fn renderer(&self) -> Option<&Arc<Renderer>> {
        self.renderer.as_ref()
    }

    /// Frames counted so far.
    pub fn frames(&self) -> u64 {
        self.run.frames()
    }

    /// The startup options.
    pub fn startup_options(&self) -> &StartupOptions {
        self.run.options()
    }

    /// Lets the window close (after the close dialog saved or discarded the edits).
    pub fn approve_close(&mut self, ctx: &egui::Context) {
        self.dialogs.close_approved = true;
        ctx.send_viewport_cmd(egui::ViewportCommand::Close);
    }
}

impl eframe::App for StudioApp {
    fn ui(&mut self, ui: &mut egui::Ui, frame: &mut eframe::Frame) {
        let frame_start = Instant::now();
        let ctx = ui.ctx().clone();
        self.diagnostics.stats.begin_frame();
        self.poll_open(&ctx);
        self.poll_bind();
        self.handle_dropped_files(&ctx);
        self.hold_close_with_unsaved_edits(&ctx);
        self.shortcuts(&ctx);
        crate::benchmark_drag::step(
            self.run.options().drag_benchmark,
            self.run.frames(),
            self.project.doc.as_mut(),
            &mut self.diagnostics,
        );
        let doc = self.project.doc.as_mut();
        self.timeline.advance(&ctx, doc, &mut self.diagnostics);
        let page_files = self.run.options().page_files.clone();
        let actions = menu_bar_ui(
            ui,
            &self.project,
            &mut self.view.layout,
            &mut self.dialogs,
            page_files.as_deref(),
        );
        self.apply_all(actions, &ctx);
        let doc = self.project.doc.as_ref();
        let help = &mut self.dialogs.help;
        status_bar_ui(ui, doc, &self.tools.selection, &self.diagnostics, help);
        let doc = self.project.doc.as_mut();
        timeline_ui(ui, doc, &mut self.timeline, &mut self.diagnostics);
        let (doc, view, tools) = (self.project.doc.as_mut(), &mut self.view, &mut self.tools);
        let offload = self.run.options().weights_offload.clone();
        inspector_ui(
            ui,
            doc,
            view,
            tools,
            &mut self.diagnostics,
            offload.as_deref(),
        );
        let render_state = frame.wgpu_render_state().cloned();
        let gpu = match (&render_state, &self.renderer) {
            (Some(render_state), Some(renderer)) => Some(Gpu {
                render_state,
                renderer,
            }),
            _ => None,
        };
        let (doc, view, tools) = (self.project.doc.as_mut(), &mut self.view, &mut self.tools);
        views_ui(ui, gpu, doc, view, tools, &mut self.diagnostics);
        let actions = dialogs_ui(&ctx, &mut self.dialogs);
        self.apply_all(actions, &ctx);
        if let Some(pending) = &self.pending_open
            && opening_ui(&ctx, pending)
        {
            self.cancel_open();
        }
        self.autosave();
        // A web page keeps its own title (eframe's web backend has no window title).
        if self.run.options().page_files.is_none() {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(self.title()));
        }
        self.diagnostics
            .stats
            .end_frame(frame_start.elapsed().as_secs_f64() * 1e3);
        self.run
            .frame_end(&ctx, &mut self.diagnostics, self.quit_requested);
    }

    /// The web edition's page reaches the app through this (`eframe::WebRunner::app_mut`).
    #[cfg(target_arch = "wasm32")]
    fn as_any_mut(&mut self) -> Option<&mut dyn std::any::Any> {
        Some(&mut *self)
    }

    fn on_exit(&mut self) {
        self.run.write_frame_stats(&mut self.diagnostics);
        // A clean exit: the recovery file is not needed (unsaved edits were asked about).
        if !self.unsaved() || self.dialogs.close_approved {
            self.project.state_dir.clear_recovery();
        }
    }
}

impl StudioApp {
    /// The window's shortcuts, then the keys of the view under the mouse (none while a text
    /// field has the focus).
    fn shortcuts(&mut self, ctx: &egui::Context) {
        if ctx.memory(|m| m.focused().is_some()) {
            return;
        }
        let page_files = self.run.options().page_files.is_some();
        let actions = crate::shortcuts::document_shortcuts(ctx, &mut self.dialogs, page_files);
        self.apply_all(actions, ctx);
        if self.tools.interaction.transform.is_none() {
            let actions = crate::shortcuts::editing_shortcuts(ctx);
            self.apply_all(actions, ctx);
        }
        let (doc, view, tools) = (self.project.doc.as_mut(), &mut self.view, &mut self.tools);
        view_keys(ctx, doc, view, tools, &mut self.diagnostics);
    }

    /// The window title: the session's file (or the character), • with unsaved edits.
    fn title(&self) -> String {
        match &self.project.doc {
            Some(d) => format!(
                "cagerig studio — {}{}",
                self.project
                    .session_path
                    .as_ref()
                    .map_or_else(|| d.source.display_name(), |p| p.display().to_string()),
                if self.unsaved() { " •" } else { "" }
            ),
            None => "cagerig studio".into(),
        }
    }

    /// Autosave to the recovery file, at most every two seconds, after edits (not in
    /// `--screenshot` or `--script` runs).
    fn autosave(&mut self) {
        // The web edition has no file system to write a recovery file to (the page asks
        // before it is closed with unsaved edits).
        if self.run.autosaves() && self.run.options().page_files.is_none() {
            let log = &mut self.diagnostics.log;
            self.project.autosave(self.timeline.time, log);
        }
    }

    /// A request to close the window while edits are unsaved is held back and asked about
    /// (scripted runs close without asking).
    fn hold_close_with_unsaved_edits(&mut self, ctx: &egui::Context) {
        if ctx.input(|i| i.viewport().close_requested())
            && self.unsaved()
            && !self.dialogs.close_approved
            && !self.run.ends_by_itself()
        {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.dialogs.confirm = Some(AfterConfirm::Close);
        }
    }

    /// Starts a Bind with automatic weights, as the Skeleton panel's Bind button does.
    pub fn bind_automatic(&mut self) {
        let offload = self.run.options().weights_offload.clone();
        match self.project.doc.as_mut() {
            Some(doc) => crate::skeleton_panel::bind_automatic(
                doc,
                &mut self.diagnostics,
                offload.as_deref(),
            ),
            None => self.diagnostics.log.error("bind: no rig is open"),
        }
    }

    /// A finished background Bind becomes the rig (one undo step); the views then show the
    /// new weights Ω of the selected joint (the first when none is).
    pub fn poll_bind(&mut self) {
        let Some(doc) = self.project.doc.as_mut() else {
            return;
        };
        match doc.poll_bind() {
            None => {}
            Some(Ok(line)) => {
                self.diagnostics.log.info(line);
                let joints = doc.session.skeleton().len();
                let selection = &mut self.tools.selection;
                if selection.joint.is_none_or(|j| j >= joints) {
                    selection.joint = Some(0);
                }
                self.view.color_mode = crate::view_state::ColorMode::Weights;
            }
            Some(Err(e)) => self.diagnostics.log.error(format!("bind: {e}")),
        }
    }

    fn handle_dropped_files(&mut self, ctx: &egui::Context) {
        if let Some(page) = &self.run.options().page_files {
            for file in ctx.input(|i| i.raw.dropped_files.clone()) {
                page.open_dropped(file);
            }
            return;
        }
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
}
