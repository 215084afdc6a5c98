//! Small sessions for the unit tests of the session's modules.

use super::{RigParts, RigSession, SessionOptions};
use crate::demo;

/// The built-in bar at resolution 8, bound with the default options.
pub(crate) fn bar() -> RigSession {
    let rig = demo::builtin("bar", Some(8)).unwrap();
    let parts = RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
    RigSession::new(parts, SessionOptions::default()).unwrap().0
}
