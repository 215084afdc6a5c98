//! A parsed `.cagerig` session file put back onto the rig its source opened: the binding made in
//! the studio rebuilt (when the file has one), then the saved state — the rig's editable state,
//! the keys and the skeleton being built — checked against that rig and restored. This is the
//! part of opening a session that a damaged or hostile file reaches once it has parsed; every
//! mismatch is an error naming the file, nothing panics, and sizes are checked before anything
//! is allocated from them. The studio and the `session_file` fuzz target both go through
//! [`restore_session`].

use std::path::{Path, PathBuf};

use thiserror::Error;

use crate::document::{DocError, Document};
use crate::rig_open::OpenedRig;
use crate::session_file::SessionFile;

/// Why a parsed session file does not fit the rig its source opened.
#[derive(Debug, Error)]
pub enum RestoreError {
    /// The skeleton and weights bound in the studio (`binding`) do not fit the character.
    #[error(
        "{path}: the skeleton bound in the studio cannot be rebuilt: {message}",
        path = path.display()
    )]
    Binding { path: PathBuf, message: String },
    /// The skeleton being built (`state.draft`) breaks what the editor keeps true of one.
    #[error(
        "{path}: the skeleton being built (\"state\".\"draft\") is damaged: {source}",
        path = path.display()
    )]
    Draft {
        path: PathBuf,
        #[source]
        source: crate::skeleton_draft::DraftError,
    },
    /// The saved state (`state`) does not fit the rig.
    #[error(
        "{path}: the saved state does not fit the rig {rig}: {source}",
        path = path.display()
    )]
    State {
        path: PathBuf,
        rig: String,
        #[source]
        source: Box<DocError>,
    },
}

/// The document of session `file` (read from `path`, which names it in errors) on `opened`, the
/// rig its source opened: the saved binding adopted, then the saved state restored. The
/// timeline position and cameras are the caller's to apply.
pub fn restore_session(
    path: &Path,
    file: &SessionFile,
    opened: OpenedRig,
) -> Result<Document, RestoreError> {
    if let Some(draft) = &file.state.draft {
        draft.validate().map_err(|source| RestoreError::Draft {
            path: path.to_path_buf(),
            source,
        })?;
    }
    let mut doc = Document::new(file.source.clone(), opened.session).with_rigged(opened.rigged);
    if let Some(binding) = &file.binding {
        let session = binding
            .bind(&doc.session)
            .map_err(|message| RestoreError::Binding {
                path: path.to_path_buf(),
                message,
            })?;
        doc.adopt_binding(session);
    }
    let mut state = file.state.clone();
    state.binding = doc.snapshot().binding;
    doc.restore(&state).map_err(|source| RestoreError::State {
        path: path.to_path_buf(),
        rig: file.source.display_name(),
        source: Box::new(source),
    })?;
    Ok(doc)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rig_open::{RigSource, open_rig};

    fn bar() -> RigSource {
        RigSource::Builtin {
            name: "bar".into(),
            resolution: Some(4),
        }
    }

    fn edited_file() -> SessionFile {
        let opened = open_rig(&bar()).unwrap();
        let mut doc = Document::new(bar(), opened.session);
        doc.execute(&crate::document::Command::RotateJoint {
            joint: 1,
            axis: glam::DVec3::Z,
            angle: 0.4,
        })
        .unwrap();
        doc.session_file(0.5)
    }

    #[test]
    fn a_saved_state_is_restored_exactly() {
        let file = edited_file();
        let doc =
            restore_session(Path::new("a.cagerig"), &file, open_rig(&bar()).unwrap()).unwrap();
        assert_eq!(doc.snapshot().rig, file.state.rig);
        assert_eq!(doc.session_file(0.5), file);
    }

    #[test]
    fn a_state_of_another_rig_is_refused_naming_the_file_and_the_rig() {
        let mut file = edited_file();
        file.state.rig.rest_cage.pop();
        let err = match restore_session(Path::new("b.cagerig"), &file, open_rig(&bar()).unwrap()) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("a state with one cage vertex too few was restored"),
        };
        assert!(
            err.contains("b.cagerig") && err.contains("builtin:bar") && err.contains("saved state"),
            "{err}"
        );
    }

    /// Regression: a draft whose parent is out of range or forms a cycle was restored, and the
    /// editor indexed its joints with it (a panic drawing the rest view or re-parenting).
    #[test]
    fn a_damaged_skeleton_draft_is_refused_naming_the_file_and_the_joint() {
        let opened = open_rig(&bar()).unwrap();
        let mut file = edited_file();
        let mut draft = crate::skeleton_draft::SkeletonDraft::from_session(&opened.session);
        draft.joints[2].parent = Some(99);
        file.state.draft = Some(draft.clone());
        let err = match restore_session(Path::new("d.cagerig"), &file, opened) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("a draft with parent 99 of 4 joints was restored"),
        };
        assert!(
            err.contains("d.cagerig") && err.contains("draft") && err.contains("99"),
            "{err}"
        );
        draft.joints[2].parent = Some(3);
        draft.joints[3].parent = Some(2);
        file.state.draft = Some(draft);
        let err = match restore_session(Path::new("e.cagerig"), &file, open_rig(&bar()).unwrap()) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("a draft with a parent cycle was restored"),
        };
        assert!(
            err.contains("e.cagerig") && err.contains("below it"),
            "{err}"
        );
    }

    #[test]
    fn a_binding_of_another_character_is_refused_naming_the_file() {
        let mut file = edited_file();
        let opened = open_rig(&bar()).unwrap();
        let mut binding = crate::saved_binding::SavedBinding::of(&opened.session);
        binding.rest_mesh.truncate(3);
        file.binding = Some(binding);
        let err = match restore_session(Path::new("c.cagerig"), &file, opened) {
            Err(e) => e.to_string(),
            Ok(_) => panic!("a binding of 3 vertices was rebuilt on the bar"),
        };
        assert!(
            err.contains("c.cagerig")
                && err.contains("mesh and")
                && err.contains("cannot be rebuilt"),
            "{err}"
        );
    }
}
