//! The open document with what belongs to it: the session file it was saved to or opened
//! from, what was saved and autosaved, the state directory (recovery file, recent files), and
//! the animations of the character it was opened from; saving, autosave, undo / redo, export
//! and animation import.

use std::path::{Path, PathBuf};
use std::time::Duration;

use web_time::Instant;

use cagerig_formats::{ImportedAnimation, MorphTargets};

use crate::diagnostics::Log;
use crate::document::Document;
use crate::keys::Track;
use crate::session_file::{SessionFile, StateDir};

/// The document and its files.
pub struct Project {
    /// The document (`None` only until the first rig is opened).
    pub doc: Option<Document>,
    /// Where the session was last saved or opened from.
    pub session_path: Option<PathBuf>,
    /// `doc.edits` when last saved.
    pub saved_edits: u64,
    /// `doc.edits` when last autosaved.
    autosaved_edits: u64,
    last_autosave: Instant,
    pub state_dir: StateDir,
    /// Animations of the open glTF / FBX character (File > Load animation).
    pub animations: Vec<ImportedAnimation>,
    /// Their morph targets (played as cage keys, see [`Project::load_character_animation`]).
    pub morph_targets: MorphTargets,
}

impl Project {
    /// No document yet, with the recovery file and recent files in `state_dir`.
    pub fn new(state_dir: StateDir) -> Self {
        Self {
            doc: None,
            session_path: None,
            saved_edits: 0,
            autosaved_edits: 0,
            last_autosave: Instant::now(),
            state_dir,
            animations: Vec::new(),
            morph_targets: MorphTargets::default(),
        }
    }

    /// Puts `doc` in place of the document (nothing saved yet, no character animations).
    pub fn set_document(&mut self, doc: Document) {
        self.doc = Some(doc);
        self.animations.clear();
        self.morph_targets = Default::default();
        self.saved_edits = 0;
        self.autosaved_edits = 0;
    }

    /// Whether the document has edits not saved in a session file.
    pub fn unsaved(&self) -> bool {
        self.doc
            .as_ref()
            .is_some_and(|d| d.edits != self.saved_edits)
    }

    /// Saves the session to `path` (atomically), with the playhead at `time` and the views'
    /// `cameras`.
    pub fn save_to(
        &mut self,
        path: &Path,
        time: f64,
        cameras: Option<[[f64; 7]; 2]>,
        log: &mut Log,
    ) -> bool {
        let Some((file, edits)) = self.session_file_to_save(time, cameras, log) else {
            return false;
        };
        match file.write(path) {
            Ok(()) => {
                self.saved_edits = edits;
                self.session_path = Some(path.to_path_buf());
                self.state_dir.add_recent(path);
                log.info(format!("saved session {}", path.display()));
                true
            }
            Err(e) => {
                log.error(e.to_string());
                false
            }
        }
    }

    /// The session file's name (`<character>.cagerig`) and text, for the web edition's
    /// download (logs why when there is none).
    pub fn session_text(
        &self,
        time: f64,
        cameras: Option<[[f64; 7]; 2]>,
        log: &mut Log,
    ) -> Option<(String, String)> {
        let (file, _) = self.session_file_to_save(time, cameras, log)?;
        let name = format!("{}.cagerig", file_stem_of(&file.source));
        match file.to_text(Path::new(&name)) {
            Ok(text) => Some((name, text)),
            Err(e) => {
                log.error(e.to_string());
                None
            }
        }
    }

    /// The session file of the document, with the playhead at `time` and the views' `cameras`,
    /// and the edit count it holds; logs why when no rig is open.
    fn session_file_to_save(
        &self,
        time: f64,
        cameras: Option<[[f64; 7]; 2]>,
        log: &mut Log,
    ) -> Option<(SessionFile, u64)> {
        let Some(doc) = &self.doc else {
            log.error("nothing to save: no rig is open");
            return None;
        };
        let mut file = doc.session_file(time);
        file.cameras = cameras;
        Some((file, doc.edits))
    }

    /// The document's edits are saved (the web edition's download was taken).
    pub fn mark_saved(&mut self) {
        if let Some(doc) = &self.doc {
            self.saved_edits = doc.edits;
        }
    }

    /// The autosave is up to date with the document (e.g. just opened from a session file).
    pub fn mark_autosaved(&mut self) {
        self.autosaved_edits = self.saved_edits;
    }

    /// Writes the recovery file now, with the playhead at `time` (true when written).
    pub fn autosave_now(&mut self, time: f64, log: &mut Log) -> bool {
        let Some(doc) = &self.doc else { return false };
        let file = doc.session_file(time);
        let edits = doc.edits;
        self.last_autosave = Instant::now();
        match self.state_dir.write_recovery(&file) {
            Ok(()) => {
                self.autosaved_edits = edits;
                true
            }
            Err(e) => {
                log.error(format!("autosave failed: {e}"));
                false
            }
        }
    }

    /// Autosave to the recovery file, at most every two seconds, after edits (not during a
    /// drag).
    pub fn autosave(&mut self, time: f64, log: &mut Log) {
        let Some(doc) = &self.doc else { return };
        if doc.edits == self.autosaved_edits
            || doc.in_gesture()
            || self.last_autosave.elapsed() < Duration::from_secs(2)
        {
            return;
        }
        self.autosave_now(time, log);
    }

    /// Undo, logging when there is nothing to undo or it failed.
    pub fn undo(&mut self, log: &mut Log) {
        let Some(doc) = &mut self.doc else { return };
        match doc.undo() {
            Ok(true) => {}
            Ok(false) => log.info("nothing to undo"),
            Err(e) => log.error(format!("undo: {e}")),
        }
    }

    /// Redo, logging when there is nothing to redo or it failed.
    pub fn redo(&mut self, log: &mut Log) {
        let Some(doc) = &mut self.doc else { return };
        match doc.redo() {
            Ok(true) => {}
            Ok(false) => log.info("nothing to redo"),
            Err(e) => log.error(format!("redo: {e}")),
        }
    }

    /// Exports everything into `dir` (see [`crate::export::export_all`]).
    pub fn export_to(&self, dir: &Path, log: &mut Log) {
        let Some(doc) = &self.doc else { return };
        match crate::export::export_all(doc, dir) {
            Ok(files) => log.info(format!(
                "exported {} files to {}",
                files.len(),
                dir.display()
            )),
            Err(e) => log.error(format!("export: {e}")),
        }
    }

    /// Puts animation `index` of the glTF / FBX character on the skeleton track (one undo
    /// step); true when the keys were put in place (the playhead then goes back to 0).
    pub fn load_character_animation(&mut self, index: usize, log: &mut Log) -> bool {
        let Some(animation) = self.animations.get(index) else {
            return false;
        };
        let name = animation.name.clone();
        let Some(doc) = &mut self.doc else {
            return false;
        };
        let mut snapshot = doc.snapshot();
        let n = snapshot
            .keys
            .set_skeleton_track(&animation.track, &doc.session);
        // Morph weights (a cagerig export with a cage track): cage keys, SkelUp held.
        let mut cage_note = String::new();
        let mut warning = None;
        if let Some(weights) = &animation.morph_weights {
            match cagerig_formats::morph_cage_track(
                &doc.session,
                &self.morph_targets,
                &animation.track,
                weights,
            ) {
                Ok(fit) => {
                    let count = snapshot.keys.set_cage_track(&fit.track, &doc.session);
                    snapshot.keys.hold_rest_skeleton = true;
                    cage_note = format!(
                        " and {count} cage keys from its morph weights (SkelUp held during \
                         playback: the joint keys carry the rest joints' motion)"
                    );
                    warning = fit.warning().map(|w| format!("animation {name:?}: {w}"));
                }
                Err(e) => {
                    warning = Some(format!(
                        "animation {name:?}: its morph weights could not be played as cage keys: \
                         {e}"
                    ))
                }
            }
        }
        let restored = doc.restore_as_step("load animation", &snapshot);
        if let Some(w) = warning {
            log.warning(w);
        }
        match restored {
            Ok(()) => {
                log.info(format!("animation {name:?}: {n} skeleton keys{cage_note}"));
                true
            }
            Err(e) => {
                log.error(format!("animation {name:?}: {e}"));
                false
            }
        }
    }

    /// Replaces a track's keys with an animation file of the paper's tool (one undo step).
    pub fn import_animation(&mut self, track: Track, path: &Path, log: &mut Log) {
        let Some(doc) = &mut self.doc else { return };
        let mut keys = doc.keys.clone();
        let result = match track {
            Track::Skeleton => keys.import_skeleton_animation(path, &doc.session),
            Track::Cage => keys.import_cage_animation(path, &doc.session),
        };
        match result {
            Ok(n) => {
                let mut snapshot = doc.snapshot();
                snapshot.keys = keys;
                match doc.restore_as_step("import animation", &snapshot) {
                    Ok(()) => log.info(format!("{n} keys imported from {}", path.display())),
                    Err(e) => log.error(format!("{}: {e}", path.display())),
                }
            }
            Err(e) => log.error(e.to_string()),
        }
    }
}

/// The name a rig's files are saved under: its character file's stem, or the built-in rig's
/// name.
pub fn file_stem_of(source: &crate::rig_open::RigSource) -> String {
    use crate::rig_open::RigSource;
    match source {
        RigSource::Builtin { name, .. } => name.clone(),
        RigSource::File { path, .. } | RigSource::Memory { path, .. } => path
            .file_stem()
            .map_or_else(|| "rig".to_string(), |s| s.to_string_lossy().into_owned()),
    }
}
