//! The edit-script interpreter on arbitrary JSON, replayed on the built-in bar rig: no panic,
//! and after every step (accepted or refused) the six structures are finite.
#![no_main]

use std::sync::OnceLock;

use cagerig::script::EditScript;
use cagerig::session::{RigParts, RigSession, SessionOptions};
use libfuzzer_sys::fuzz_target;

mod finite_session;
use finite_session::all_finite;

fn bar() -> &'static RigSession {
    static SESSION: OnceLock<RigSession> = OnceLock::new();
    SESSION.get_or_init(|| {
        let rig = cagerig::demo::builtin("bar", Some(8)).unwrap();
        let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
        RigSession::new(parts, SessionOptions::default()).unwrap().0
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(script) = EditScript::parse(text) else {
        return;
    };
    let mut session = bar().clone();
    if script.validate(&session).is_err() {
        return;
    }
    for k in 0..script.steps.len().min(64) {
        let before = session.rest_cage().to_vec();
        let result = script.run_step(k, &mut session);
        assert!(all_finite(&session), "step {k} left a non-finite structure");
        if result.is_err() {
            // A refused event leaves the rig as it was.
            assert_eq!(session.rest_cage(), &before[..]);
        }
    }
});
