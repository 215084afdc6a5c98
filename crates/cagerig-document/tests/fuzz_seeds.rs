//! The seeds of the `session_file` fuzz target (`fuzz/seeds/session_file/`) are session files
//! this build writes and opens: the bar as opened, edited with keys on both tracks, with a
//! skeleton being built, with a skeleton bound in the studio, and a file source (whose state
//! the target restores onto the bar). The test fails when a seed no longer equals what the
//! document writes today (a format change); `CAGERIG_WRITE_FUZZ_SEEDS=1` rewrites them.

#![expect(clippy::unwrap_used)] // tests, benches and examples may panic on a broken fixture

use std::path::{Path, PathBuf};

use cagerig_document::binding::BindWeights;
use cagerig_document::document::{Command, Document, SkeletonEdit};
use cagerig_document::keys::Track;
use cagerig_document::rig_open::{RigSource, open_rig};
use cagerig_document::session_file::SessionFile;
use cagerig_document::session_restore::restore_session;
use glam::DVec3;

fn bar() -> RigSource {
    RigSource::Builtin {
        name: "bar".into(),
        resolution: Some(2),
    }
}

fn document() -> Document {
    Document::new(bar(), open_rig(&bar()).unwrap().session)
}

fn edited() -> Document {
    let mut doc = document();
    doc.execute(&Command::SetKey {
        track: Track::Skeleton,
        time: 0.0,
    })
    .unwrap();
    doc.execute(&Command::RotateJoint {
        joint: 1,
        axis: DVec3::Z,
        angle: 0.5,
    })
    .unwrap();
    doc.execute(&Command::MovePosedCage {
        vertices: vec![3],
        offsets: vec![DVec3::new(0.0, 0.2, 0.0)],
    })
    .unwrap();
    doc.execute(&Command::SetKey {
        track: Track::Skeleton,
        time: 1.0,
    })
    .unwrap();
    doc.execute(&Command::SetKey {
        track: Track::Cage,
        time: 0.5,
    })
    .unwrap();
    doc
}

fn with_draft() -> Document {
    let mut doc = document();
    let (lo, hi) = cagerig::mesh::bounding_box(doc.session.rest_mesh());
    doc.execute(&Command::EditSkeleton(SkeletonEdit::Add {
        position: 0.5 * (lo + hi),
        parent: Some(1),
        mirror: None,
    }))
    .unwrap();
    doc
}

fn bound() -> Document {
    let mut doc = with_draft();
    doc.bind_blocking(BindWeights::KeepBound).unwrap();
    doc
}

/// The seeds, by file name.
fn seeds() -> Vec<(&'static str, SessionFile)> {
    let mut file_source = edited().session_file(0.25);
    file_source.source = RigSource::File {
        path: "/nonexistent/bar.obj".into(),
        cage: None,
        skin: None,
        auto_cage: Some(40),
    };
    let mut with_cameras = edited().session_file(0.75);
    with_cameras.cameras = Some([[0.0, 0.0, 0.0, 20.0, 0.3, 0.2, 0.8]; 2]);
    vec![
        ("opened.cagerig", document().session_file(0.0)),
        ("edited.cagerig", with_cameras),
        ("draft.cagerig", with_draft().session_file(0.0)),
        ("bound.cagerig", bound().session_file(0.0)),
        ("file_source.cagerig", file_source),
    ]
}

/// The same JSON, numbers equal to 1e-9 relative (of at least 1).
fn same_to_round_off(a: &serde_json::Value, b: &serde_json::Value) -> bool {
    use serde_json::Value;
    match (a, b) {
        (Value::Number(x), Value::Number(y)) => match (x.as_f64(), y.as_f64()) {
            (Some(x), Some(y)) => (x - y).abs() <= 1e-9 * x.abs().max(y.abs()).max(1.0),
            _ => x == y,
        },
        (Value::Array(x), Value::Array(y)) => {
            x.len() == y.len() && x.iter().zip(y).all(|(x, y)| same_to_round_off(x, y))
        }
        (Value::Object(x), Value::Object(y)) => {
            x.len() == y.len()
                && x.iter()
                    .all(|(k, v)| y.get(k).is_some_and(|w| same_to_round_off(v, w)))
        }
        _ => a == b,
    }
}

fn seed_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../fuzz/seeds/session_file")
}

#[test]
fn the_fuzz_seeds_are_current_session_files_that_open() {
    let dir = seed_dir();
    let write = std::env::var_os("CAGERIG_WRITE_FUZZ_SEEDS").is_some();
    for (name, file) in seeds() {
        let path = dir.join(name);
        let text = serde_json::to_string(&file).unwrap();
        assert!(
            text.len() <= 8192,
            "{name}: {} bytes, over run_all.sh's -max_len",
            text.len()
        );
        if write {
            file.write(&path).unwrap();
        }
        let read = SessionFile::read(&path)
            .unwrap_or_else(|e| panic!("{e} (CAGERIG_WRITE_FUZZ_SEEDS=1 rewrites the seeds)"));
        // As written (the state's binding key is the document's, not the file's), to round-off:
        // the stored numbers come from whichever CPU wrote the seeds, and the factorisations
        // round differently on each SIMD tier.
        let (stored, now) = (
            serde_json::to_value(&read).unwrap(),
            serde_json::to_value(&file).unwrap(),
        );
        assert!(
            same_to_round_off(&stored, &now),
            "{name} differs from what this build writes:\n{stored}\n{now}"
        );
        // Every seed opens as the fuzz target opens it (a file source onto the bar).
        let source = match &read.source {
            RigSource::Builtin { .. } => read.source.clone(),
            RigSource::File { .. } | RigSource::Memory { .. } => bar(),
        };
        let doc = restore_session(&path, &read, open_rig(&source).unwrap()).unwrap();
        assert_eq!(doc.snapshot().keys, read.state.keys, "{name}");
        assert_eq!(doc.draft, read.state.draft, "{name}");
    }
}
