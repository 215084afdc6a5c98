//! `--benchmark-drag cage|rest-cage|joint`: every frame applies one event of a simulated drag
//! through the same gesture path as the mouse (a current-cage grab, a rest-cage grab, or a
//! joint rotation), so that `--frame-stats` measures the frame time of an interactive edit.

use glam::DVec3;

use crate::diagnostics::Diagnostics;
use crate::document::{Command, Document};

/// Which drag to simulate.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum DragBenchmark {
    /// Grab three current-cage vertices (C' edit: CageRev, SkelUp, skinning, CageUp).
    Cage,
    /// Grab three rest-cage vertices (C edit: M += ΦΔC, SkelUp, skinning, CageUp).
    RestCage,
    /// Rotate the middle joint (S' edit: FK, skinning, CageUp).
    Joint,
}

/// One event of the simulated drag `kind` in frame `frame` (called once per frame).
pub fn step(
    kind: Option<DragBenchmark>,
    frame: u64,
    doc: Option<&mut Document>,
    diag: &mut Diagnostics,
) {
    let Some(kind) = kind else {
        return;
    };
    let frame = frame as f64;
    let Some(doc) = doc else { return };
    let (lo, hi) = cagerig::mesh::bounding_box(doc.session.rest_cage());
    let size = (hi - lo).length();
    doc.begin_gesture("benchmark drag");
    // A small circle: every frame moves by a different offset, as a hand does.
    let phase = frame * 0.2;
    let step = 0.002 * size * DVec3::new(phase.cos(), phase.sin(), 0.0);
    let nc = doc.session.rest_cage().len();
    let vertices: Vec<usize> = (0..nc.min(3)).collect();
    let command = match kind {
        DragBenchmark::Cage => Command::MovePosedCage {
            vertices,
            offsets: vec![step],
        },
        DragBenchmark::RestCage => Command::MoveRestCage {
            vertices,
            offsets: vec![step],
        },
        DragBenchmark::Joint => Command::RotateJoint {
            joint: doc.session.skeleton().len() / 2,
            axis: DVec3::Z,
            angle: 0.01 * phase.cos(),
        },
    };
    match doc.gesture_event(&command) {
        Ok(()) => diag.stats.sync_ms += doc.last_sync_ms,
        Err(e) => diag.log.error(format!("benchmark drag: {e}")),
    }
}
