//! Switching CageUp's fit ([`CageFitKind`]) on a live rig: CageUp and Eq. 19 are rebuilt on
//! the same Φ and rows; C, S, S' and M' do not move, C' is refitted.

use super::RigSession;
use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::sync::cage_fit_kind::CageFitKind;

impl RigSession {
    /// The CageUp fit the rig was asked for (its options; Green rigs fit on the rows whatever
    /// this says, see [`RigSession::cage_fit`]).
    pub fn requested_cage_fit(&self) -> CageFitKind {
        self.options.cage_fit
    }

    /// Switches CageUp to the fit `kind` and refits C' (unless CageUp is locked). One
    /// all-or-nothing step: on an error nothing changed. Green rigs record the choice only.
    pub fn set_cage_fit(&mut self, kind: CageFitKind) -> Result<(), RigError> {
        if kind == self.options.cage_fit {
            return Ok(());
        }
        let cage = TriMesh {
            positions: self.original_rest_cage.clone(),
            triangles: self.cage_triangles.clone(),
        };
        self.rest_map.set_fit_kind(
            kind,
            &cage,
            &self.skin_weights,
            &self.skeleton_updater,
            &self.skeleton,
        )?;
        self.options.cage_fit = kind;
        if !self.locks.cage_up {
            self.fit_cage();
        }
        Ok(())
    }
}
