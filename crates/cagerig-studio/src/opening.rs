//! What can be opened (a character, a session, the recovery file), what waits for the answer
//! to the unsaved-edits question, and the background load of a rig with its progress window
//! (the application's side, which swaps the documents, is in `open_document`).

use std::cell::{Cell, RefCell};
use std::path::PathBuf;
use std::sync::{Arc, Mutex, mpsc};
use web_time::Instant;

use cagerig::session::BindStage;

use crate::rig_open::{OpenError, OpenedRig, RigSource, open_rig_with_progress};
use crate::session_file::SessionFile;

/// Something to open.
#[derive(Debug, Clone, PartialEq)]
pub enum OpenRequest {
    /// A character (files or a built-in rig).
    Rig(RigSource),
    /// A `.cagerig` session file.
    Session(PathBuf),
    /// The autosave offered at start: opened like a session, but not saved back over itself.
    Recovery(PathBuf),
}

impl OpenRequest {
    /// The name shown while loading and in the unsaved-edits question.
    pub fn display_name(&self) -> String {
        match self {
            OpenRequest::Rig(source) => source.display_name(),
            OpenRequest::Session(path) | OpenRequest::Recovery(path) => path.display().to_string(),
        }
    }
}

/// What the unsaved-edits question was asked for, done once the edits are saved or discarded.
#[derive(Debug, Clone, PartialEq)]
pub enum AfterConfirm {
    /// Close the window.
    Close,
    /// Open something in place of the current document.
    Open(OpenRequest),
}

/// A load with no thread to run on (the web target): it runs at the second poll, so that the
/// frame before it draws the progress window.
type DeferredLoad = Box<dyn FnOnce()>;

/// A rig being loaded on a background thread (on the web target, which has no threads, on the
/// main thread after one frame of the progress window).
pub struct PendingOpen {
    request: OpenRequest,
    /// The session file of a session or recovery request, read before its rig.
    session: Option<SessionFile>,
    /// When the load started; for a deferred load, when it ran (the time the page's thread
    /// spent on it).
    started: Cell<Instant>,
    result: mpsc::Receiver<Result<OpenedRig, OpenError>>,
    /// The binding's last report: its stage, the work done and its total.
    progress: Arc<Mutex<Option<(BindStage, usize, usize)>>>,
    /// The load itself when no thread runs it, and the polls it has waited.
    deferred: RefCell<Option<DeferredLoad>>,
    polls: Cell<u32>,
}

impl PendingOpen {
    /// Starts loading `source` on a background thread for `request` (with `session`, the
    /// session file of a session or recovery request, read before); gives the arguments
    /// back with the error when no thread can be started.
    pub fn spawn(
        request: OpenRequest,
        source: &RigSource,
        session: Option<SessionFile>,
    ) -> Result<Self, Box<NoThread>> {
        let (sender, receiver) = mpsc::channel();
        let job = source.clone();
        let progress = Arc::new(Mutex::new(None));
        let shared = Arc::clone(&progress);
        let work = move || {
            let report = |stage: BindStage, done: usize, total: usize| {
                if let Ok(mut slot) = shared.lock() {
                    *slot = Some((stage, done, total));
                }
            };
            // The receiver is gone only if the load was abandoned.
            let _ = sender.send(open_rig_with_progress(&job, &report));
        };
        let started = Instant::now();
        #[cfg(target_arch = "wasm32")]
        let (spawned, deferred): (std::io::Result<()>, Option<DeferredLoad>) =
            (Ok(()), Some(Box::new(work)));
        #[cfg(not(target_arch = "wasm32"))]
        let (spawned, deferred): (std::io::Result<()>, Option<DeferredLoad>) = (
            std::thread::Builder::new()
                .name("cagerig-open".into())
                .spawn(work)
                .map(drop),
            None,
        );
        match spawned {
            Ok(()) => Ok(Self {
                request,
                session,
                started: Cell::new(started),
                result: receiver,
                progress,
                deferred: RefCell::new(deferred),
                polls: Cell::new(0),
            }),
            Err(error) => Err(Box::new(NoThread {
                request,
                session,
                started,
                error,
            })),
        }
    }

    /// The result of the load once it has arrived (a deferred load runs at the second call).
    pub fn try_result(&self) -> Option<Result<OpenedRig, OpenError>> {
        self.polls.set(self.polls.get().saturating_add(1));
        if self.polls.get() >= 2
            && let Some(work) = self.deferred.borrow_mut().take()
        {
            self.started.set(Instant::now());
            work();
        }
        match self.result.try_recv() {
            Ok(result) => Some(result),
            Err(mpsc::TryRecvError::Empty) => None,
            Err(mpsc::TryRecvError::Disconnected) => Some(Err(OpenError::Interrupted)),
        }
    }

    pub fn request(&self) -> &OpenRequest {
        &self.request
    }

    /// The binding's progress: the fraction done (0…1) of its current stage and what it
    /// computes, once it has reported (reading and importing the file come before).
    pub fn progress(&self) -> Option<(f32, &'static str)> {
        let (stage, done, total) = self.progress.lock().ok().and_then(|p| *p)?;
        let fraction = if total == 0 {
            0.0
        } else {
            done as f32 / total as f32
        };
        Some((fraction, stage.label()))
    }

    /// The request, its session file and when it started.
    pub fn into_parts(self) -> (OpenRequest, Option<SessionFile>, Instant) {
        (self.request, self.session, self.started.get())
    }
}

/// No thread could be started for a background load: what it was for.
#[derive(Debug)]
pub struct NoThread {
    pub request: OpenRequest,
    pub session: Option<SessionFile>,
    pub started: Instant,
    pub error: std::io::Error,
}

/// The progress window of a background load, with a button to stop waiting (true when
/// clicked).
pub fn opening_ui(ctx: &egui::Context, pending: &PendingOpen) -> bool {
    let (name, elapsed) = (
        pending.request.display_name(),
        pending.started.get().elapsed().as_secs_f64(),
    );
    let mut cancel = false;
    egui::Window::new("Opening")
        .collapsible(false)
        .resizable(false)
        .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
        .show(ctx, |ui| {
            ui.horizontal(|ui| {
                ui.spinner();
                ui.label(format!("{name}: {elapsed:.1} s"));
            });
            match pending.progress() {
                Some((fraction, what)) => {
                    ui.add(
                        egui::ProgressBar::new(fraction)
                            .show_percentage()
                            .text(format!("{what} {:.0} %", 100.0 * fraction)),
                    );
                }
                None => {
                    ui.label("Reading the character…");
                }
            }
            ui.label("Then the coupling operators: MaxVol rows, SkelUp, CageUp and CageRev.");
            cancel = ui.button("Stop waiting").clicked();
        });
    cancel
}

#[cfg(test)]
mod tests {
    use super::{OpenRequest, PendingOpen};
    use crate::rig_open::RigSource;

    #[test]
    fn a_background_open_reports_the_bindings_progress() {
        let source = RigSource::Builtin {
            name: "bar".into(),
            resolution: None,
        };
        let pending = PendingOpen::spawn(OpenRequest::Rig(source.clone()), &source, None)
            .map_err(|e| e.error)
            .expect("a thread");
        let opened = loop {
            if let Some(result) = pending.try_result() {
                break result.expect("the bar opens");
            }
            std::thread::sleep(std::time::Duration::from_millis(5));
        };
        let (fraction, what) = pending
            .progress()
            .expect("the binding reported its progress");
        assert_eq!(what, "cage coordinates");
        assert!(
            (fraction - 1.0).abs() < 1e-6,
            "the last report is the stage's end: {fraction}"
        );
        assert!(!opened.session.rest_mesh().is_empty());
    }
}
