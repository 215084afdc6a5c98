//! The rig's state as the web page's test hook reports it, so that a browser test can compare
//! the page with the native library (`cagerig edit` on the same script) to round-off.

use cagerig::session::RigSession;
use serde::Serialize;

/// The coupled structures of a session, in the session's model space (f64, exact path).
#[derive(Debug, Serialize)]
pub struct RigState {
    /// Posed joint positions S', `#J`.
    pub posed_joints: Vec<[f64; 3]>,
    /// Rest cage C, `#C`.
    pub rest_cage: Vec<[f64; 3]>,
    /// Current cage C', `#C`.
    pub posed_cage: Vec<[f64; 3]>,
    /// The cage's triangles.
    pub cage_triangles: Vec<[u32; 3]>,
    /// Rest skin M, `#V`.
    pub rest_mesh: Vec<[f64; 3]>,
    /// Current skin M', `#V`.
    pub posed_mesh: Vec<[f64; 3]>,
}

impl RigState {
    /// The state of `session`.
    pub fn of(session: &RigSession) -> Self {
        let rows = |points: &[glam::DVec3]| points.iter().map(|p| p.to_array()).collect();
        Self {
            posed_joints: session.posed_joints().map(|p| p.to_array()).collect(),
            rest_cage: rows(session.rest_cage()),
            posed_cage: rows(session.posed_cage()),
            cage_triangles: session.cage_triangles().to_vec(),
            rest_mesh: rows(session.rest_mesh()),
            posed_mesh: rows(session.posed_mesh()),
        }
    }

    /// The state as JSON (every f64 written so that it reads back to the same bits).
    pub fn to_json(&self) -> String {
        serde_json::to_string(self).unwrap_or_else(|e| format!("{{\"error\":\"{e}\"}}"))
    }
}

/// Ω as JSON `{"joints": #J, "rows": [[[joint, weight], …], …]}`, one row per vertex (every
/// f64 written so that it reads back to the same bits).
pub fn weights_json(weights: &cagerig::SkinWeights) -> String {
    let rows: Vec<Vec<(u32, f64)>> = (0..weights.num_vertices())
        .map(|v| {
            let (joints, values) = weights.row(v);
            joints.iter().copied().zip(values.iter().copied()).collect()
        })
        .collect();
    serde_json::json!({"joints": weights.num_joints(), "rows": rows}).to_string()
}

#[cfg(test)]
mod tests {
    use super::RigState;

    #[test]
    fn the_state_of_a_builtin_rig_reads_back_bit_for_bit() {
        let rig = cagerig::demo::builtin("bar", None).unwrap();
        let parts =
            cagerig::session::RigParts::new(rig.mesh, rig.skeleton, rig.skin_weights, rig.cage);
        let (session, _) = cagerig::session::RigSession::new(parts, Default::default()).unwrap();
        let state = RigState::of(&session);
        assert_eq!(state.posed_cage.len(), session.rest_cage().len());
        assert_eq!(state.posed_mesh.len(), session.num_vertices());
        let back: serde_json::Value = serde_json::from_str(&state.to_json()).unwrap();
        let x = back["posed_mesh"][7][1].as_f64().unwrap();
        assert_eq!(x.to_bits(), session.posed_mesh()[7].y.to_bits());
    }
}
