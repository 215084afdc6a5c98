//! The user interactions on the cages (Section 4, Figures 3–4): a rest-cage edit C, and a
//! current-cage edit C' turned into a rest-cage edit by CageRev.

use super::RigSession;
use crate::error::RigError;
use glam::DVec3;

impl RigSession {
    /// C edit: moves rest-cage vertices `vertices` by `offsets` (one per vertex, or one for all).
    /// M follows incrementally (M += Φ[:, k]·ΔC_k), then SkelUp, skinning and CageUp.
    pub fn move_rest_cage(
        &mut self,
        vertices: &[usize],
        offsets: &[DVec3],
    ) -> Result<(), RigError> {
        self.save_checkpoint();
        let result = self.move_rest_cage_event(vertices, offsets);
        self.finish_event(result)
    }

    /// [`RigSession::move_rest_cage`] without the checkpoint.
    fn move_rest_cage_event(
        &mut self,
        vertices: &[usize],
        offsets: &[DVec3],
    ) -> Result<(), RigError> {
        self.check_cage_edit(vertices, offsets)?;
        let mut dense = std::mem::take(&mut self.scratch_cage_a);
        scatter_edit(vertices, offsets, &mut dense);
        let mut touched = std::mem::take(&mut self.scratch_touched);
        let mut compact = std::mem::take(&mut self.scratch_cage_b);
        touched.clear();
        for (k, d) in dense.iter().enumerate() {
            if *d != DVec3::ZERO {
                compact[touched.len()] = *d;
                touched.push(k);
            }
        }
        self.apply_rest_cage_delta_sparse(&touched, &compact[..touched.len()]);
        self.scratch_cage_a = dense;
        self.scratch_cage_b = compact;
        self.scratch_touched = touched;
        self.sync_from_rest_cage();
        Ok(())
    }

    /// C' edit: moves current-cage vertices by `offsets`. CageRev (Eq. 19) turns the edit into a
    /// rest-cage edit (refactorising first if the skeleton moved since the last grab); the full
    /// chain then re-fits C', which lands on the requested positions (exactly under LBS, or with
    /// the ghost fit for DQS/CoR).
    pub fn move_posed_cage(
        &mut self,
        vertices: &[usize],
        offsets: &[DVec3],
    ) -> Result<(), RigError> {
        self.save_checkpoint();
        let result = self.move_posed_cage_event(vertices, offsets);
        self.finish_event(result)
    }

    /// [`RigSession::move_posed_cage`] without the checkpoint.
    fn move_posed_cage_event(
        &mut self,
        vertices: &[usize],
        offsets: &[DVec3],
    ) -> Result<(), RigError> {
        self.check_cage_edit(vertices, offsets)?;
        self.check_posed_cage_fitted()?;
        if self.locks.cage_up {
            return Err(RigError::Invalid(
                "the current cage C' cannot be edited while CageUp is locked (CageRev assumes \
                 C' is CageUp's fit of M'); unlock CageUp first"
                    .into(),
            ));
        }
        let mut posed_delta = std::mem::take(&mut self.scratch_cage_a);
        scatter_edit(vertices, offsets, &mut posed_delta);
        let mut rest_delta = std::mem::take(&mut self.scratch_cage_b);
        let solved = self.reverse_cage(&posed_delta, &mut rest_delta);
        if solved.is_ok() {
            for (c, d) in self.rest_cage.iter_mut().zip(&rest_delta) {
                *c += *d;
            }
            self.start_fit_from_grab(&posed_delta);
        }
        self.scratch_cage_a = posed_delta;
        self.scratch_cage_b = rest_delta;
        solved?;
        self.rest_and_sync_from_cage();
        Ok(())
    }
}

/// Per-cage-vertex offsets of an edit (`#C`): one offset per listed vertex, or one for all;
/// a vertex listed twice moves by the sum. `vertices` and `offsets` are checked beforehand.
pub(super) fn scatter_edit(vertices: &[usize], offsets: &[DVec3], dense: &mut [DVec3]) {
    dense.iter_mut().for_each(|d| *d = DVec3::ZERO);
    for (i, &v) in vertices.iter().enumerate() {
        dense[v] += offsets[if offsets.len() == 1 { 0 } else { i }];
    }
}
