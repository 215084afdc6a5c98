//! The check shared by the fuzz targets that drive a session.

use cagerig::session::RigSession;

/// Whether the six structures (rest and posed mesh, cage and joints) are finite.
pub fn all_finite(s: &RigSession) -> bool {
    s.rest_mesh().iter().all(|p| p.is_finite())
        && s.posed_mesh().iter().all(|p| p.is_finite())
        && s.rest_cage().iter().all(|p| p.is_finite())
        && s.posed_cage().iter().all(|p| p.is_finite())
        && s.rest_joints().all(|p| p.is_finite())
        && s.posed_joints().all(|p| p.is_finite())
}
