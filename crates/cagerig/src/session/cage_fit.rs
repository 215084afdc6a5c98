//! Switching CageUp's fit ([`CageFitKind`]) on a live rig: CageUp and Eq. 19 are rebuilt on
//! the same Φ and rows; C, S, S' and M' do not move, C' is refitted.

use super::RigSession;
use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::sync::cage_fit_kind::CageFitKind;

impl RigSession {
    /// The CageUp fit the rig was asked for (its options; see [`RigSession::cage_fit`] for the
    /// fit it has).
    pub fn requested_cage_fit(&self) -> CageFitKind {
        self.options.cage_fit
    }

    /// Switches CageUp to the fit `kind` and refits C' (unless CageUp is locked). One
    /// all-or-nothing step: on an error nothing changed. Green rigs switch their fit's
    /// regulariser (a rig whose cage has no prior keeps the fit on the rows alone).
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
