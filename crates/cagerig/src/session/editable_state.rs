//! The editable state of a session as one value — what an editor's undo history and session
//! files hold — and the user's SkelUp / CageUp locks.
//!
//! Everything else in a [`RigSession`] (M, M', the skinning transforms, the CoR centres) is
//! derived from this state by the sync chain, so restoring it restores the rig: C, the joint
//! positions of S, the pose parameters and the skinning method bit for bit; M = ΦC and M' to
//! round-off (M is recomputed in full where edits had updated it incrementally).

use glam::{DQuat, DVec3};
use serde::{Deserialize, Serialize};

use super::unfitted_cage::UnfittedCagePolicy;
use crate::coords::stretched_normals::FaceTermKind;
use crate::coords_kind::CoordsKind;
use crate::skinning::SkinningMethod;
use crate::sync::cage_fit_kind::CageFitKind;

/// Sync operators the user has switched off (the paper tool's locks). While a lock is on the
/// structures are deliberately out of consensus; switching it off runs the full sync again.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct SyncLocks {
    /// SkelUp off: rest-cage edits (C) no longer move the rest joints (S stays).
    pub skel_up: bool,
    /// CageUp off: posing (S') no longer refits the current cage (C' stays); C' edits are
    /// refused meanwhile (CageRev assumes C' is CageUp's fit).
    pub cage_up: bool,
}

impl SyncLocks {
    /// Whether every sync operator is on (the rig is in consensus).
    pub fn none(self) -> bool {
        !self.skel_up && !self.cage_up
    }
}

/// A session's editable state; all `#C` or `#J` long.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EditableState {
    /// C, rest cage (`#C`).
    pub rest_cage: Vec<DVec3>,
    /// Rest joint positions A of S (`#J`, world space); ΨC unless SkelUp was locked.
    pub rest_joints: Vec<DVec3>,
    /// C' (`#C`) while CageUp is locked, or while it is unfitted (a Green CageUp found no
    /// current cage: [`super::UnfittedCagePolicy`]): then it is state, not derived; `None`
    /// otherwise (C' is CageUp's fit of M').
    pub posed_cage: Option<Vec<DVec3>>,
    /// Local rotations q_j of the current pose (`#J`).
    pub rotations: Vec<DQuat>,
    /// Local scales s_j of the current pose (`#J`).
    pub scales: Vec<DVec3>,
    /// d_j, current local translation minus the rest bone offset (`#J`).
    pub translation_offsets: Vec<DVec3>,
    /// The skinning method.
    pub skinning: SkinningMethod,
    /// The SkelUp / CageUp locks.
    pub locks: SyncLocks,
    /// The cage coordinates the rig is bound with (absent in older files: mean value).
    #[serde(default)]
    pub coords: CoordsKind,
    /// What an event does when a Green CageUp finds no current cage (absent in older files:
    /// refuse it).
    #[serde(default)]
    pub unfitted_cage: UnfittedCagePolicy,
    /// CageUp's fit (absent in older files: the default, regularised; C' is derived, so an
    /// older file opens with the same C, S and S').
    #[serde(default)]
    pub cage_fit: CageFitKind,
    /// Green rigs' face term (absent in older files: the default, fold-safe; a Green rig saved
    /// with Lipman's term before it was recorded reopens with the fold-safe one).
    #[serde(default)]
    pub green_face_term: FaceTermKind,
}
