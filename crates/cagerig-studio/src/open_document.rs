//! Opening characters and sessions into the studio: unsaved edits are asked about first, the
//! rig is loaded on a background thread while the window keeps drawing (a progress window
//! shows what is loading), and the new document replaces the old one only once it is ready (a
//! failure leaves the old one as it was); the new document starts with nothing selected, the
//! playhead at 0 and the views framed on it.

use std::path::Path;
use std::time::Duration;

use web_time::Instant;

use crate::app::StudioApp;
use crate::document::Document;
use crate::opening::{AfterConfirm, NoThread, OpenRequest, PendingOpen};
use crate::rig_open::{OpenError, OpenedRig, RigSource, open_rig};
use crate::session_file::SessionFile;
use crate::session_restore::restore_session;
use crate::timeline::TimelineState;

impl StudioApp {
    /// Opens a path by its extension (a session, or a character), asking about unsaved edits
    /// first.
    pub fn open_path(&mut self, path: &Path) {
        let is_session = path
            .extension()
            .is_some_and(|e| e.eq_ignore_ascii_case("cagerig"));
        let request = if is_session {
            OpenRequest::Session(path.to_path_buf())
        } else {
            let vertices = if self.dialogs.cage_vertices == 0 {
                100
            } else {
                self.dialogs.cage_vertices
            };
            OpenRequest::Rig(RigSource::File {
                path: path.to_path_buf(),
                cage: None,
                auto_cage: self.dialogs.generate_cage.then_some(vertices),
                skin: Some(self.dialogs.skin.trim())
                    .filter(|s| !s.is_empty())
                    .map(str::to_owned),
            })
        };
        self.request_open(request);
    }

    /// Opens `request` in place of the current document: with unsaved edits (in an interactive
    /// run) asks Save / Don't save / Cancel first, then loads in the background.
    pub fn request_open(&mut self, request: OpenRequest) {
        if self.unsaved() && !self.run.is_scripted() {
            self.dialogs.confirm = Some(AfterConfirm::Open(request));
        } else {
            self.start_open(request);
        }
    }

    /// Carries out what the unsaved-edits question was asked for.
    pub fn continue_after_confirm(&mut self, ctx: &egui::Context, after: AfterConfirm) {
        match after {
            AfterConfirm::Close => self.approve_close(ctx),
            AfterConfirm::Open(request) => self.start_open(request),
        }
    }

    /// Starts loading `request` on a background thread (a load still pending is abandoned: its
    /// result is dropped). A session file is read first; if it cannot be read, that is logged
    /// and nothing else happens.
    pub fn start_open(&mut self, request: OpenRequest) {
        let Some((source, session)) = self.source_of(&request) else {
            return;
        };
        match PendingOpen::spawn(request, &source, session) {
            Ok(pending) => self.pending_open = Some(pending),
            Err(no_thread) => {
                let NoThread {
                    request,
                    session,
                    started,
                    error,
                } = *no_thread;
                self.diagnostics.log.warning(format!(
                    "no thread to load in the background ({error}): loading now"
                ));
                let result = open_rig(&source);
                self.finish_open(request, session, started, result);
            }
        }
    }

    /// Opens `request` now, blocking (at start and in scripted runs).
    pub fn open_blocking(&mut self, request: OpenRequest) {
        self.pending_open = None;
        let Some((source, session)) = self.source_of(&request) else {
            return;
        };
        let started = Instant::now();
        let result = open_rig(&source);
        self.finish_open(request, session, started, result);
    }

    /// Whether a rig is loading in the background.
    pub fn is_opening(&self) -> bool {
        self.pending_open.is_some()
    }

    /// Abandons a background load (its result is dropped when it arrives).
    pub fn cancel_open(&mut self) {
        if let Some(pending) = self.pending_open.take() {
            self.diagnostics.log.info(format!(
                "stopped waiting for {}",
                pending.request().display_name()
            ));
        }
    }

    /// Once per frame: takes the result of a background load when it has arrived.
    pub(crate) fn poll_open(&mut self, ctx: &egui::Context) {
        let Some(pending) = &self.pending_open else {
            return;
        };
        let Some(result) = pending.try_result() else {
            ctx.request_repaint_after(Duration::from_millis(50));
            return;
        };
        if let Some(pending) = self.pending_open.take() {
            let (request, session, started) = pending.into_parts();
            self.finish_open(request, session, started, result);
        }
        ctx.request_repaint();
    }

    /// The rig source of a request, and its session file (read now) for a session.
    fn source_of(&mut self, request: &OpenRequest) -> Option<(RigSource, Option<SessionFile>)> {
        match request {
            OpenRequest::Rig(source) => Some((source.clone(), None)),
            OpenRequest::Session(path) | OpenRequest::Recovery(path) => {
                match SessionFile::read(path) {
                    Ok(file) => Some((file.source.clone(), Some(file))),
                    Err(e) => {
                        self.diagnostics.log.error(e.to_string());
                        if self.project.doc.is_none() {
                            self.open_blocking(OpenRequest::Rig(RigSource::default()));
                        }
                        None
                    }
                }
            }
        }
    }

    /// Puts a loaded rig (and the state of a session) in place, or logs why it could not be
    /// opened (the current document then stays).
    fn finish_open(
        &mut self,
        request: OpenRequest,
        session: Option<SessionFile>,
        started: Instant,
        result: Result<OpenedRig, OpenError>,
    ) {
        let opened = match result {
            Ok(opened) => opened,
            Err(e) => {
                match &request {
                    OpenRequest::Rig(_) => self.diagnostics.log.error(format!("cannot open: {e}")),
                    OpenRequest::Session(path) | OpenRequest::Recovery(path) => self
                        .diagnostics
                        .log
                        .error(format!("{}: opening its rig: {e}", path.display())),
                }
                if self.project.doc.is_none() && request != OpenRequest::Rig(RigSource::default()) {
                    self.open_blocking(OpenRequest::Rig(RigSource::default()));
                }
                return;
            }
        };
        match (request, session) {
            (OpenRequest::Session(path), Some(file)) => {
                self.put_session(&path, file, opened);
                self.project.session_path = Some(path.clone());
                self.project.state_dir.add_recent(&path);
            }
            (OpenRequest::Recovery(path), Some(file)) => {
                self.put_session(&path, file, opened);
                self.project.session_path = None;
            }
            (request, _) => self.put_rig(request, started, opened),
        }
    }

    /// A loaded character becomes the document.
    fn put_rig(&mut self, request: OpenRequest, started: Instant, opened: OpenedRig) {
        let source = opened.source.clone();
        let s = &opened.session;
        let log = &mut self.diagnostics.log;
        log.info(format!(
            "opened {}: {} vertices, {} joints, {} cage vertices ({:.0} ms)",
            request.display_name(),
            s.num_vertices(),
            if opened.rigged { s.skeleton().len() } else { 0 },
            s.rest_cage().len(),
            started.elapsed().as_secs_f64() * 1e3
        ));
        for w in &opened.warnings {
            match w.severity() {
                cagerig::Severity::Note => log.info(w.to_string()),
                cagerig::Severity::Warning => log.warning(w.to_string()),
            }
        }
        if !opened.animations.is_empty() {
            log.info(format!(
                "{} animation(s) in the file: {} (File > Load animation puts one on the \
                 skeleton track)",
                opened.animations.len(),
                opened
                    .animations
                    .iter()
                    .map(|a| a.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ));
        }
        if let RigSource::File { path, .. } = &source {
            self.project.state_dir.add_recent(path);
        }
        self.set_document(Document::new(source, opened.session).with_rigged(opened.rigged));
        self.project.animations = opened.animations;
        self.project.morph_targets = opened.morph_targets;
        self.project.session_path = None;
    }

    /// A loaded session's rig with the session's state restored becomes the document.
    fn put_session(&mut self, path: &Path, file: SessionFile, opened: OpenedRig) {
        let doc = match restore_session(path, &file, opened) {
            Ok(doc) => doc,
            Err(e) => {
                self.diagnostics.log.error(e.to_string());
                return;
            }
        };
        let edits = doc.edits;
        self.set_document(doc);
        self.project.saved_edits = edits;
        self.project.mark_autosaved();
        self.timeline.time = file.time;
        if let Some(cameras) = file.cameras {
            for (view, key) in self.view.views.iter_mut().zip(cameras) {
                if let Some(camera) = crate::viewport::camera_from_key(key) {
                    view.camera = camera;
                    view.framed = true;
                }
            }
        }
        self.diagnostics
            .log
            .info(format!("opened session {}", path.display()));
    }

    /// `doc` becomes the document: nothing selected, the playhead at 0, the views framed on
    /// it when next shown, nothing saved yet.
    pub(crate) fn set_document(&mut self, doc: Document) {
        self.project.set_document(doc);
        self.tools.reset_for_new_document();
        self.timeline = TimelineState::default();
        self.view.unframe();
    }
}
