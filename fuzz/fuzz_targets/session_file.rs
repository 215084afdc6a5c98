//! `.cagerig` session files on arbitrary bytes, opened as the studio opens them: parsed
//! (`SessionFile::parse`), written back and parsed again to the same content, then restored
//! onto the rig of their source (`restore_session`: the saved binding rebuilt, the state, keys
//! and skeleton draft checked and restored) and exercised as the editor would right after
//! opening — both views' skeletons drawn, the keys played, a joint rotated and undone, the
//! draft edited and bound with its carried weights, the session saved again.
//!
//! Sources: a built-in rig opens at the file's resolution when it is small (up to
//! `MAX_VERTICES` skin vertices); a larger one goes only through the library's memory check
//! (`check_fits`, which `demo::builtin` runs first): refused or not, it is not built, so a huge
//! resolution costs nothing here and must not allocate. A file source is never opened — the
//! target must not read arbitrary paths — its state is restored onto the built-in bar
//! (resolution 2) instead,
//! so the restore path is fuzzed whatever the source says. No panic, no allocation beyond
//! libFuzzer's limits, every structure finite after every event.
#![no_main]

use std::collections::HashMap;
use std::path::Path;
use std::sync::Mutex;

use cagerig::session::RigSession;
use cagerig_document::binding::BindWeights;
use cagerig_document::document::{Command, Document, SkeletonEdit};
use cagerig_document::rig_open::{OpenedRig, RigSource, open_rig};
use cagerig_document::session_file::SessionFile;
use cagerig_document::session_restore::restore_session;
use glam::DVec3;
use libfuzzer_sys::fuzz_target;

mod finite_session;
use finite_session::all_finite;

/// The largest built-in rig the target builds (skin vertices).
const MAX_VERTICES: u64 = 2_000;

/// Opened built-in rigs by (name, resolution); `None`: refused.
type Cache = HashMap<(String, Option<usize>), Option<RigSession>>;

fn opened(name: &str, resolution: Option<usize>) -> Option<OpenedRig> {
    static CACHE: Mutex<Option<Cache>> = Mutex::new(None);
    let source = RigSource::Builtin {
        name: name.to_string(),
        resolution,
    };
    let mut guard = CACHE.lock().unwrap_or_else(|e| e.into_inner());
    let cache = guard.get_or_insert_with(HashMap::new);
    let session = cache
        .entry((name.to_string(), resolution))
        .or_insert_with(|| open_rig(&source).ok().map(|o| o.session))
        .clone()?;
    Some(OpenedRig {
        source,
        session,
        warnings: Vec::new(),
        files: Vec::new(),
        animations: Vec::new(),
        morph_targets: Default::default(),
        rigged: true,
    })
}

/// What the views draw of the skeleton: every parent names a drawn joint, every position is
/// finite, one name per joint.
fn check_shown(doc: &Document) {
    for rest in [true, false] {
        let shown = doc.shown_skeleton(rest);
        let n = shown.positions.len();
        assert_eq!(shown.parents.len(), n);
        assert_eq!(shown.names.len(), n);
        assert!(
            shown.parents.iter().flatten().all(|&p| p < n),
            "a parent out of range"
        );
        assert!(shown.positions.iter().all(|p| p.is_finite()));
    }
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let path = Path::new("fuzz.cagerig");
    let Ok(file) = SessionFile::parse(text, path) else {
        return;
    };
    // What parsed is written back as it was.
    let written = serde_json::to_string(&file).expect("a parsed session file serialises");
    let again = SessionFile::parse(&written, path).expect("a written session file parses");
    assert_eq!(again, file, "the session file changed on a write and read");

    let opened = match &file.source {
        RigSource::Builtin { name, resolution } => {
            let fits = cagerig::demo::builtin_names()
                .contains(&name.as_str())
                .then(|| {
                    let (vertices, cage_vertices) =
                        cagerig::memory_estimate::builtin_size(name, *resolution);
                    (
                        vertices,
                        cagerig::memory_estimate::check_fits("fuzz", vertices, cage_vertices),
                    )
                });
            match fits {
                // Too large to hold: the studio refuses it before building (check_fits).
                Some((_, Err(_))) => return,
                // Fits, but too slow for a fuzz run.
                Some((vertices, Ok(()))) if vertices > MAX_VERTICES => return,
                _ => match opened(name, *resolution) {
                    Some(o) => o,
                    None => return,
                },
            }
        }
        // A file (or a file's bytes, which no session file holds) opens onto the small bar.
        RigSource::File { .. } | RigSource::Memory { .. } => match opened("bar", Some(2)) {
            Some(o) => o,
            None => return,
        },
    };
    let Ok(mut doc) = restore_session(path, &file, opened) else {
        return;
    };
    assert!(all_finite(&doc.session), "a restored state is not finite");
    check_shown(&doc);

    // The keys play.
    let duration = doc.keys.duration();
    for t in [0.0, 0.5 * duration, duration, file.time] {
        if doc.sample(t).is_ok() {
            assert!(
                all_finite(&doc.session),
                "playback at {t} left a non-finite structure"
            );
        }
    }
    // A joint rotated and undone.
    let before = doc.snapshot();
    if doc
        .execute(&Command::RotateJoint {
            joint: 0,
            axis: DVec3::Z,
            angle: 0.3,
        })
        .is_ok()
    {
        assert!(all_finite(&doc.session));
        doc.undo().expect("undo after a rotation");
        assert_eq!(doc.snapshot().keys, before.keys);
    }
    // The draft edited and bound with its carried weights.
    if let Some(draft) = doc.draft.clone() {
        let n = draft.len();
        let edits = [
            SkeletonEdit::Move {
                joint: 0,
                position: DVec3::new(0.1, 0.2, 0.3),
                mirror: Some(doc.mirror()),
            },
            SkeletonEdit::SetParent {
                joint: n.saturating_sub(1),
                parent: Some(0),
            },
            SkeletonEdit::Rename {
                joint: 0,
                name: "fuzz.L".into(),
            },
            SkeletonEdit::Delete {
                joint: n / 2,
                mirror: true,
            },
        ];
        for edit in edits {
            let _ = doc.execute(&Command::EditSkeleton(edit));
            check_shown(&doc);
        }
        if doc.bind_blocking(BindWeights::KeepBound).is_ok() {
            assert!(
                all_finite(&doc.session),
                "a bind left a non-finite structure"
            );
            check_shown(&doc);
        }
    }
    // Saved again, the session parses.
    let saved =
        serde_json::to_string(&doc.session_file(file.time)).expect("the session serialises");
    SessionFile::parse(&saved, path).expect("a saved session parses");
});
