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

use std::sync::{Arc, OnceLock};

use glam::{DAffine3, DVec3, Vec3};

use super::display_rest_map::DisplayRestMapProduct;
use crate::cage_coords::CageCoords;
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
pub(super) struct Stored<K> {
    kernel: K,
    revision: u64,
}

/// The f32 kernels (built on first use), their scratch, the f64 row kernels of CageUp and the
/// displayed M'.
#[derive(Debug, Clone)]
pub(super) struct DisplayPath {
    pub(super) lbs: Option<Stored<LbsF32>>,
    pub(super) dqs: Option<Stored<DqsF32>>,
    pub(super) cor: Option<Stored<CorF32>>,
    pub(super) blended: Option<Stored<BlendedF32>>,
    pub(super) lbs_scratch: LbsF32Scratch,
    pub(super) dqs_scratch: DqsF32Scratch,
    pub(super) cor_scratch: CorF32Scratch,
    pub(super) blended_scratch: BlendedF32Scratch,
    /// Ω restricted to the MaxVol rows, for the exact DQS/CoR/blended rows (LBS rows use the
    /// session's ghost LBS).
    pub(super) rows_dqs: DualQuaternionSkinning,
    pub(super) rows_cor: CorSkinning,
    /// The blended kernel of the MaxVol rows (`None` when the rig has no DQ blend weights).
    pub(super) rows_blended: Option<BlendedSkinning>,
    pub(super) rows_dqs_scratch: DqsScratch,
    pub(super) rows_cor_scratch: CorScratch,
    /// CoR centres of the MaxVol rows, `#rows`.
    pub(super) rows_centres: Vec<DVec3>,
    /// Displayed M' (`#V`, f32).
    pub positions: Vec<Vec3>,
    /// The exact M' of the current state, skinned on demand.
    pub exact: OnceLock<Vec<DVec3>>,
    /// The product M̃ = Φ̃·[C; g] of the session's [`super::DisplayRestMap`] (by default Φ
    /// rounded to f32; built at the first current-cage edit; `None` before, or when the backend
    /// could not hold it, and then M is computed exactly).
    pub(super) coords: Option<Arc<dyn DisplayRestMapProduct>>,
    /// Φ and the kind's extra coordinates (ψ) on CageUp's rows alone (`#R` rows each, built
    /// with `coords`): the exact rows of M from a few contiguous kilobytes, the bits of the
    /// full product's rows (2.1 ms → µs at 133k vertices on Green's 170 columns, whose entries
    /// of a row lie in as many pages).
    pub(super) row_coords: Option<(CageCoords, Option<CageCoords>)>,
    /// 0..#R, the rows of `row_coords`.
    pub(super) row_indices: Vec<usize>,
    /// Displayed M (`#V`, f32): Φ̃·C after a current-cage edit, else the exact M rounded.
    pub rest_positions: Vec<Vec3>,
    /// The rest revision `rest_positions` belongs to.
    pub(super) rest_positions_revision: Option<u64>,
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

/// The skinning method of the displayed M', with the data its f32 kernel is built from.
#[derive(Debug, Clone, Copy)]
pub(super) enum MethodF32<'a> {
    Lbs,
    Dqs,
    /// With the CoR centres (`#V`).
    Cor(&'a [DVec3]),
    /// With the DQ blend weights b (`#V`).
    Blended(&'a DqBlendWeights),
}

/// The inputs of one f32 skinning of the displayed M'.
pub(super) struct SkinF32<'a> {
    pub(super) method: MethodF32<'a>,
    pub(super) transforms: &'a [DAffine3],
    pub(super) weights: &'a SkinWeights,
    /// Rest revision of `rest`.
    pub(super) revision: u64,
}

impl SkinF32<'_> {
    /// Brings the method's f32 kernel to `rest` (`#V`) and skins into `display.positions`.
    pub(super) fn apply<P: RestPoint>(
        &self,
        display: &mut DisplayPath,
        rest: &[P],
    ) -> Result<(), RigError> {
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
