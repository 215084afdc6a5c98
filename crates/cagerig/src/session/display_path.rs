//! The display path: the current skin M' that is drawn, skinned by the f32 kernels, while the
//! exact f64 state drives the sync operators.
//!
//! With [`DisplayPrecision::F32`] an event skins all of M' with [`LbsF32`] / [`DqsF32`] /
//! [`CorF32`] / [`BlendedF32`] into [`RigSession::display_mesh`] (max |f32 − f64| ≤ 2e-6 of the bounding-box
//! diagonal, asserted by `tests/display_path.rs`; measured 3e-7–5e-7 on the subdivided Arm), and
//! CageUp reads the MaxVol rows of M' skinned **exactly** in f64 by row kernels of the same rule
//! (bit-identical to the rows of the full f64 M'): C', C, S and S' are the same bits as on the
//! exact path. [`RigSession::posed_mesh`] stays exact: in this mode it is skinned in f64 on the
//! first call after an event (and kept until the next one).
//!
//! A current-cage edit changes C everywhere, and the exact M = ΦC then reads all of Φ (79 MB at
//! 133k × 74). On this path it computes instead the drawn rest mesh M̃ = Φ̃·C with Φ rounded to
//! f32 ([`DisplayCageCoords`], half the bytes) and the exact M on CageUp's MaxVol rows only
//! ([`CageCoords::apply_rows`], the bits of the full product), which is all the sync operators
//! read; [`RigSession::rest_mesh`] computes the whole exact M on its first call, and any
//! rest-cage edit does so before it applies its increment. The f32 kernels then skin M̃.
//!
//! Green rigs take the same path with the face terms as extra columns: M̃ = [φ̃ ψ̃]·[C; g(C)]
//! (one f32 product, g(C) exact in f64) and the exact rows φ_R C + ψ_R g(C), the bits of the full
//! product's rows ([`CageCoords::add_rows`]).

use std::sync::OnceLock;

use glam::{DAffine3, DVec3, Vec3};
use rayon::prelude::*;

use super::RigSession;
use super::rest_map::RestMeshState;
use super::skinning::ActiveSkinning;
use crate::cage_coords::{CageCoords, DisplayCageCoords};
use crate::error::RigError;
use crate::skin_weights::SkinWeights;
use crate::skinning::{
    BlendedF32, BlendedF32Scratch, BlendedSkinning, CorF32, CorF32Scratch, CorScratch, CorSkinning,
    DqBlendWeights, DqsF32, DqsF32Scratch, DqsScratch, DualQuaternionSkinning, LbsF32,
    LbsF32Scratch, RestPoint,
};

/// Precision of the displayed current skin M'.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum DisplayPrecision {
    /// M' is skinned in f64 on every event (the default; every output is exact).
    #[default]
    Exact,
    /// M' for display is skinned in f32; sync operators and [`RigSession::posed_mesh`] stay
    /// exact.
    F32,
}

/// An f32 kernel with the rest revision its stored rest mesh (and centres) belongs to.
#[derive(Debug, Clone)]
struct Stored<K> {
    kernel: K,
    revision: u64,
}

/// The f32 kernels (built on first use), their scratch, the f64 row kernels of CageUp and the
/// displayed M'.
#[derive(Debug, Clone)]
pub(super) struct DisplayPath {
    lbs: Option<Stored<LbsF32>>,
    dqs: Option<Stored<DqsF32>>,
    cor: Option<Stored<CorF32>>,
    blended: Option<Stored<BlendedF32>>,
    lbs_scratch: LbsF32Scratch,
    dqs_scratch: DqsF32Scratch,
    cor_scratch: CorF32Scratch,
    blended_scratch: BlendedF32Scratch,
    /// Ω restricted to the MaxVol rows, for the exact DQS/CoR/blended rows (LBS rows use the
    /// session's ghost LBS).
    rows_dqs: DualQuaternionSkinning,
    rows_cor: CorSkinning,
    /// The blended kernel of the MaxVol rows (`None` when the rig has no DQ blend weights).
    rows_blended: Option<BlendedSkinning>,
    rows_dqs_scratch: DqsScratch,
    rows_cor_scratch: CorScratch,
    /// CoR centres of the MaxVol rows, `#rows`.
    rows_centres: Vec<DVec3>,
    /// Displayed M' (`#V`, f32).
    pub positions: Vec<Vec3>,
    /// The exact M' of the current state, skinned on demand.
    pub exact: OnceLock<Vec<DVec3>>,
    /// Φ̃, Φ rounded to f32 (built at the first current-cage edit; `None` before, or when its
    /// memory could not be reserved, and then M is computed exactly).
    coords: Option<DisplayCageCoords>,
    /// Φ and the kind's extra coordinates (ψ) on CageUp's rows alone (`#R` rows each, built
    /// with `coords`): the exact rows of M from a few contiguous kilobytes, the bits of the
    /// full product's rows (2.1 ms → µs at 133k vertices on Green's 170 columns, whose entries
    /// of a row lie in as many pages).
    row_coords: Option<(CageCoords, Option<CageCoords>)>,
    /// 0..#R, the rows of `row_coords`.
    row_indices: Vec<usize>,
    /// Displayed M (`#V`, f32): Φ̃·C after a current-cage edit, else the exact M rounded.
    pub rest_positions: Vec<Vec3>,
    /// The rest revision `rest_positions` belongs to.
    rest_positions_revision: Option<u64>,
    /// The exact M while the session keeps it on the MaxVol rows only, computed on demand.
    pub exact_rest: OnceLock<Vec<DVec3>>,
}

impl DisplayPath {
    /// `blend`: the rig's DQ blend weights (`#V`), whose rows the blended row kernel reads.
    pub fn new(
        skin_weights: &SkinWeights,
        rows: &[usize],
        blend: Option<&DqBlendWeights>,
    ) -> Result<Self, RigError> {
        let nj = skin_weights.num_joints();
        let row_weights = skin_weights.select_rows(rows);
        let rows_blended = blend
            .map(|b| BlendedSkinning::new(&row_weights, &b.select_rows(rows)))
            .transpose()?;
        Ok(Self {
            lbs: None,
            dqs: None,
            cor: None,
            blended: None,
            lbs_scratch: LbsF32Scratch::new(nj),
            dqs_scratch: DqsF32Scratch::new(nj),
            cor_scratch: CorF32Scratch::new(nj),
            blended_scratch: BlendedF32Scratch::new(nj),
            rows_dqs: DualQuaternionSkinning::new(&row_weights),
            rows_cor: CorSkinning::new(&row_weights),
            rows_blended,
            rows_dqs_scratch: DqsScratch::new(nj),
            rows_cor_scratch: CorScratch::new(nj),
            rows_centres: vec![DVec3::ZERO; rows.len()],
            positions: vec![Vec3::ZERO; skin_weights.num_vertices()],
            exact: OnceLock::new(),
            coords: None,
            row_coords: None,
            row_indices: (0..rows.len()).collect(),
            rest_positions: vec![Vec3::ZERO; skin_weights.num_vertices()],
            rest_positions_revision: None,
            exact_rest: OnceLock::new(),
        })
    }
}

/// Brings a stored kernel to `revision`: builds it, or refreshes its rest data.
fn refresh<K>(
    slot: &mut Option<Stored<K>>,
    revision: u64,
    build: impl FnOnce() -> Result<K, RigError>,
    update: impl FnOnce(&mut K) -> Result<(), RigError>,
) -> Result<&K, RigError> {
    let mut stored = match slot.take() {
        Some(stored) => stored,
        None => Stored {
            kernel: build()?,
            revision,
        },
    };
    if stored.revision != revision {
        update(&mut stored.kernel)?;
        stored.revision = revision;
    }
    Ok(&slot.insert(stored).kernel)
}

impl DisplayPath {
    /// Forgets the exact M computed on demand (M was just set in full).
    pub(super) fn forget_exact_rest(&mut self) {
        self.exact_rest = OnceLock::new();
    }
}

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
            display.coords = match self.rest_map.extra_coords() {
                None => DisplayCageCoords::try_new(coords),
                Some(extra) => DisplayCageCoords::try_new_concatenated(&[coords, extra]),
            };
        }
        let Some(coords) = &display.coords else {
            return self.rest_from_cage_in_full();
        };
        self.rest_map.update_terms(&self.rest_cage);
        coords.apply_concatenated(
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

/// The skinning method of the displayed M', with the data its f32 kernel is built from.
#[derive(Debug, Clone, Copy)]
enum MethodF32<'a> {
    Lbs,
    Dqs,
    /// With the CoR centres (`#V`).
    Cor(&'a [DVec3]),
    /// With the DQ blend weights b (`#V`).
    Blended(&'a DqBlendWeights),
}

/// The inputs of one f32 skinning of the displayed M'.
struct SkinF32<'a> {
    method: MethodF32<'a>,
    transforms: &'a [DAffine3],
    weights: &'a SkinWeights,
    /// Rest revision of `rest`.
    revision: u64,
}

impl SkinF32<'_> {
    /// Brings the method's f32 kernel to `rest` (`#V`) and skins into `display.positions`.
    fn apply<P: RestPoint>(&self, display: &mut DisplayPath, rest: &[P]) -> Result<(), RigError> {
        let (transforms, weights, revision) = (self.transforms, self.weights, self.revision);
        match self.method {
            MethodF32::Dqs => {
                let dqs = refresh(
                    &mut display.dqs,
                    revision,
                    || DqsF32::new(weights, rest),
                    |k| k.set_rest_positions(rest),
                )?;
                dqs.apply(transforms, &mut display.dqs_scratch, &mut display.positions);
            }
            MethodF32::Blended(blend) => {
                let blended = refresh(
                    &mut display.blended,
                    revision,
                    || BlendedF32::new(weights, blend, rest),
                    |k| k.set_rest_positions(rest),
                )?;
                blended.apply(
                    transforms,
                    &mut display.blended_scratch,
                    &mut display.positions,
                );
            }
            MethodF32::Cor(centres) => {
                let cor = refresh(
                    &mut display.cor,
                    revision,
                    || CorF32::new(weights, rest, centres),
                    |k| k.set_rest_positions(rest, centres),
                )?;
                cor.apply(transforms, &mut display.cor_scratch, &mut display.positions);
            }
            MethodF32::Lbs => {
                let lbs = refresh(
                    &mut display.lbs,
                    revision,
                    || LbsF32::new(weights, rest),
                    |k| k.set_rest_positions(rest),
                )?;
                lbs.apply(transforms, &mut display.lbs_scratch, &mut display.positions);
            }
        }
        Ok(())
    }
}
