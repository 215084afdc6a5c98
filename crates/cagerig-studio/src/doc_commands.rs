//! The document's commands as the panels run them: one undo step each, a failure logged, the
//! sync time of the session event added to the frame's.

use crate::diagnostics::Diagnostics;
use crate::document::{Command, Document};

/// Runs a command as one undo step, logging a failure.
pub fn run_command(doc: &mut Document, command: &Command, diag: &mut Diagnostics) -> bool {
    match doc.execute(command) {
        Ok(()) => {
            diag.stats.sync_ms += doc.last_sync_ms;
            true
        }
        Err(e) => {
            diag.log.error(format!("{}: {e}", command.label()));
            false
        }
    }
}

/// Samples the keys at `time` (playback, scrubbing), logging a failure.
pub fn sample_keys(doc: &mut Document, time: f64, diag: &mut Diagnostics) {
    match doc.sample(time) {
        Ok(_) => diag.stats.sync_ms += doc.last_sync_ms,
        Err(e) => diag.log.error(format!("sampling the keys: {e}")),
    }
}
