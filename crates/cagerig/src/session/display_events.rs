//! The session on the f32 display path: switching it, M̃ and M̃' per event, and the exact
//! meshes on demand (see [`super::display_path`]).

use std::sync::OnceLock;

use super::RigSession;
use super::display_path::{DisplayPath, DisplayPrecision, MethodF32, SkinF32};
use super::rest_map::RestMeshState;
use super::skinning::ActiveSkinning;
use crate::error::RigError;
use crate::skinning::cor::CorScratch;
use crate::skinning::dqs::DqsScratch;
use glam::{DAffine3, DVec3, Vec3};
use rayon::prelude::*;

impl RigSession {
    /// Switches the precision of the displayed M' (see [`DisplayPrecision`]); the current state
    /// is re-skinned.
    pub fn set_display_precision(&mut self, precision: DisplayPrecision) -> Result<(), RigError> {
        self.ensure_exact_rest_mesh();
        self.display = match precision {
            DisplayPrecision::Exact => None,
            DisplayPrecision::F32 => Some(Box::new(DisplayPath::new(
                &self.skin_weights,
                self.rest_map.rows(),
                self.dq_blend_weights(),
            )?)),
        };
        self.skin();
        if !self.locks.cage_up {
            self.fit_cage();
        }
        Ok(())
    }

    /// The precision of the displayed M'.
    pub fn display_precision(&self) -> DisplayPrecision {
        if self.display.is_some() {
            DisplayPrecision::F32
        } else {
            DisplayPrecision::Exact
        }
    }

    /// The displayed current skin M' in f32 (`#V`) under [`DisplayPrecision::F32`]; `None` on
    /// the exact path (use [`RigSession::posed_mesh`]).
    pub fn display_mesh(&self) -> Option<&[Vec3]> {
        self.display.as_deref().map(|d| &d.positions[..])
    }

    /// The displayed rest skin M in f32 (`#V`) under [`DisplayPrecision::F32`]: Φ̃·C after a
    /// current-cage edit, else the exact M rounded; `None` on the exact path (use
    /// [`RigSession::rest_mesh`]).
    pub fn display_rest_mesh(&self) -> Option<&[Vec3]> {
        self.display.as_deref().map(|d| &d.rest_positions[..])
    }

    /// After a current-cage edit (or a cage keyframe) changed C everywhere: on the display path
    /// M̃ = Φ̃·C (Green: [φ̃ ψ̃]·[C; g(C)]) for display and the exact M on the MaxVol rows (see the
    /// module notes), else M in full. Then the CoR centres.
    pub(super) fn rest_from_cage_for_event(&mut self) {
        let Some(display) = self.display.as_deref_mut() else {
            return self.rest_from_cage_in_full();
        };
        if display.coords.is_none() {
            let coords = self.rest_map.coords();
            let backend = &self.options.display_rest_map;
            display.coords = match self.rest_map.extra_coords() {
                None => backend.upload(&[coords]),
                Some(extra) => backend.upload(&[coords, extra]),
            };
        }
        let Some(coords) = &display.coords else {
            return self.rest_from_cage_in_full();
        };
        self.rest_map.update_terms(&self.rest_cage);
        coords.apply(
            &self.rest_cage,
            self.rest_map.terms(),
            &mut display.rest_positions,
        );
        let rows = self.rest_map.rows();
        let (vertex_rows, extra_rows) = display.row_coords.get_or_insert_with(|| {
            (
                self.rest_map.coords().rows_as_coords(rows),
                self.rest_map
                    .extra_coords()
                    .map(|extra| extra.rows_as_coords(rows)),
            )
        });
        vertex_rows.apply_rows(
            &display.row_indices,
            &self.rest_cage,
            &mut self.scratch_rows_rest,
        );
        if let Some(extra_rows) = extra_rows {
            extra_rows.add_rows(
                &display.row_indices,
                self.rest_map.terms(),
                &mut self.scratch_rows_rest,
            );
        }
        for (&row, p) in rows.iter().zip(&self.scratch_rows_rest) {
            self.rest_mesh[row] = *p;
        }
        display.exact_rest = OnceLock::new();
        self.rest_mesh_changed();
        // M̃ above is the drawn M of this new revision.
        if let Some(display) = self.display.as_deref_mut() {
            display.rest_positions_revision = Some(self.rest_revision);
        }
        self.rest_map.set_mesh_state(RestMeshState::MapOnRows);
        self.centres_from_cage_in_full();
    }

    /// Makes `rest_mesh` the whole exact M again if it was kept on the MaxVol rows only.
    pub(super) fn ensure_exact_rest_mesh(&mut self) {
        if self.rest_map.mesh_state() != RestMeshState::MapOnRows {
            return;
        }
        match self
            .display
            .as_deref_mut()
            .and_then(|d| d.exact_rest.take())
        {
            Some(exact) => self.rest_mesh = exact,
            None => self
                .rest_map
                .rest_mesh_at_terms(&self.rest_cage, &mut self.rest_mesh),
        }
        self.rest_map.set_mesh_state(RestMeshState::Map);
    }

    /// The exact M while it is kept on the MaxVol rows only (computed on first use).
    pub(super) fn exact_rest_mesh<'a>(&'a self, display: &'a DisplayPath) -> &'a [DVec3] {
        display.exact_rest.get_or_init(|| {
            let mut exact = vec![DVec3::ZERO; self.rest_map.coords().num_vertices()];
            self.rest_map
                .rest_mesh_at_terms(&self.rest_cage, &mut exact);
            exact
        })
    }

    /// Marks the rest mesh M (and the CoR centres) as changed for the display kernels.
    pub(super) fn rest_mesh_changed(&mut self) {
        self.rest_revision = self.rest_revision.wrapping_add(1);
    }

    /// Skins the displayed M' in f32 and forgets the exact M' of the previous state.
    pub(super) fn skin_display(&mut self) -> Result<(), RigError> {
        let Some(display) = self.display.as_deref_mut() else {
            return Ok(());
        };
        display.exact = OnceLock::new();
        let revision = self.rest_revision;
        if display.rest_positions_revision != Some(revision) {
            // M changed exactly (never while it is kept on the rows only: see
            // `rest_from_cage_for_event`): round it for display.
            display
                .rest_positions
                .par_iter_mut()
                .zip(&self.rest_mesh)
                .with_min_len(1 << 14)
                .for_each(|(o, p)| *o = p.as_vec3());
            display.rest_positions_revision = Some(revision);
        }
        // The f32 kernels read the exact M when there is one (their local frame then rounds
        // differences, not absolute coordinates), else M̃.
        let rest_display = std::mem::take(&mut display.rest_positions);
        let skin = SkinF32 {
            method: match self.skinning.active() {
                ActiveSkinning::Lbs => MethodF32::Lbs,
                ActiveSkinning::Dqs => MethodF32::Dqs,
                ActiveSkinning::Cor(cor) => MethodF32::Cor(&cor.centres),
                ActiveSkinning::Blended(blended) => MethodF32::Blended(blended.dq_blend_weights()),
                ActiveSkinning::External(_) => {
                    display.rest_positions = rest_display;
                    return self.skin_display_from_exact();
                }
            },
            transforms: &self.posed_from_rest,
            weights: &self.skin_weights,
            revision,
        };
        let result = if self.rest_map.mesh_state() == RestMeshState::MapOnRows {
            skin.apply(display, &rest_display)
        } else {
            skin.apply(display, &self.rest_mesh)
        };
        display.rest_positions = rest_display;
        result
    }

    /// The displayed M' of a method with no f32 kernel (an external one): its exact M' of the
    /// exact M, rounded; the exact M' is kept for [`RigSession::posed_mesh`] and CageUp.
    fn skin_display_from_exact(&mut self) -> Result<(), RigError> {
        self.ensure_exact_rest_mesh();
        let mut exact = vec![DVec3::ZERO; self.rest_mesh.len()];
        let nj = self.skeleton.len();
        self.skin_exact(
            &self.rest_mesh,
            &mut DqsScratch::new(nj),
            &mut CorScratch::new(nj),
            &mut exact,
        );
        let Some(display) = self.display.as_deref_mut() else {
            return Ok(());
        };
        for (o, p) in display.positions.iter_mut().zip(&exact) {
            *o = p.as_vec3();
        }
        display.exact = OnceLock::from(exact);
        Ok(())
    }

    /// The MaxVol rows of M', exact, into `scratch_rows_posed` (display path only; the exact
    /// path reads them from the full M').
    pub(super) fn skin_rows_exact(&mut self) {
        let Some(display) = self.display.as_deref_mut() else {
            return;
        };
        let rows = self.rest_map.rows();
        for (r, &row) in self.scratch_rows_rest.iter_mut().zip(rows) {
            *r = self.rest_mesh[row];
        }
        let transforms: &[DAffine3] = &self.posed_from_rest;
        match (self.skinning.active(), &display.rows_blended) {
            // The rows' blended kernel exists whenever the rig has b (`DisplayPath::new`);
            // were it missing, LBS (the ghost fit's consensus) is the defined result.
            (ActiveSkinning::Lbs, _) | (ActiveSkinning::Blended(_), None) => self.ghost_lbs.apply(
                transforms,
                &self.scratch_rows_rest,
                &mut self.scratch_rows_posed,
            ),
            (ActiveSkinning::Blended(_), Some(rows_blended)) => rows_blended.apply(
                transforms,
                &self.scratch_rows_rest,
                &mut display.rows_dqs_scratch,
                &mut self.scratch_rows_posed,
            ),
            (ActiveSkinning::Dqs, _) => display.rows_dqs.apply(
                transforms,
                &self.scratch_rows_rest,
                &mut display.rows_dqs_scratch,
                &mut self.scratch_rows_posed,
            ),
            // An external method has no row kernel: the rows of its exact M' (which `skin`
            // computed for display).
            (ActiveSkinning::External(bound), _) => {
                let exact = display.exact.get_or_init(|| {
                    let mut out = vec![DVec3::ZERO; self.rest_mesh.len()];
                    bound.apply(transforms, &self.rest_mesh, &mut out);
                    out
                });
                for (p, &row) in self.scratch_rows_posed.iter_mut().zip(rows) {
                    *p = exact[row];
                }
            }
            (ActiveSkinning::Cor(cor), _) => {
                for (c, &row) in display.rows_centres.iter_mut().zip(rows) {
                    *c = cor.centres[row];
                }
                display.rows_cor.apply(
                    transforms,
                    &self.scratch_rows_rest,
                    &display.rows_centres,
                    &mut display.rows_cor_scratch,
                    &mut self.scratch_rows_posed,
                );
            }
        }
    }

    /// The exact M' of the current state on the display path (skinned in f64 on first use).
    pub(super) fn exact_posed_mesh<'a>(&'a self, display: &'a DisplayPath) -> &'a [DVec3] {
        display.exact.get_or_init(|| {
            let mut out = vec![DVec3::ZERO; self.rest_mesh.len()];
            let nj = self.skeleton.len();
            self.skin_exact(
                self.rest_mesh(),
                &mut DqsScratch::new(nj),
                &mut CorScratch::new(nj),
                &mut out,
            );
            out
        })
    }
}
