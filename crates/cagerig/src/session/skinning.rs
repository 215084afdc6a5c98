//! The session's skinning component: M' from M under the method in use (Section 3, Eq. 1–3 and
//! 14), each method held with the data it needs, so that a method without its data cannot be
//! selected.
//!
//! | method | data |
//! |---|---|
//! | [`ActiveSkinning::Lbs`] | Ω (the LBS kernel every rig has) |
//! | [`ActiveSkinning::Dqs`] | Ω (the DQS kernel every rig has) |
//! | [`ActiveSkinning::Cor`] | the CoR centres p_i = Λ·C and their kernel ([`CorState`]) |
//! | [`ActiveSkinning::Blended`] | the rig's DQ blend weights b ([`BlendedSkinning`]) |
//! | [`ActiveSkinning::External`] | the method passed in, bound to the rig ([`BoundSkinning`]) |
//!
//! A method's data is built once (the CoR centres on the first switch to CoR, an external
//! method's binding with the session) and kept while another method runs; the CoR centres then
//! lag behind C and are refreshed when CoR runs next.

use std::sync::Arc;

use glam::{DAffine3, DVec3};

use super::external_skinning::BoundSkinning;
use crate::cage_coords::CageCoords;
use crate::cor_centres::CorCentresOptions;
use crate::error::RigError;
use crate::skin_weights::SkinWeights;
use crate::skinning::blended::BlendedSkinning;
use crate::skinning::cor::{CorScratch, CorSkinning};
use crate::skinning::dqs::{DqsScratch, DualQuaternionSkinning};
use crate::skinning::lbs::LinearBlendSkinning;
use crate::skinning::{DqBlendWeights, SkinningMethod};
use crate::sparse_rows::SparseRows;

/// CoR data: Λ = S·Φ (`#V × #C`, Eq. 14) and the centres Λ·C (`#V`).
#[derive(Debug, Clone)]
pub(super) struct CorState {
    pub(super) centre_coords: CageCoords,
    pub(super) centres: Vec<DVec3>,
    /// The centres lag behind C while another skinning method is active (they are refreshed
    /// in full when CoR skinning runs next), so cage edits under LBS/DQS do not pay for Λ·C.
    pub(super) stale: bool,
    skinning: CorSkinning,
}

impl CorState {
    /// The CoR state of Λ `centre_coords` (`#V × #C`) and its centres (`#V`) for Ω
    /// `skin_weights`.
    pub(super) fn new(
        centre_coords: CageCoords,
        centres: Vec<DVec3>,
        skin_weights: &SkinWeights,
    ) -> Self {
        Self {
            centre_coords,
            centres,
            stale: false,
            skinning: CorSkinning::new(skin_weights),
        }
    }
}

/// Where the CoR cage coordinates Λ come from when CoR skinning is first selected.
#[derive(Debug, Clone)]
pub(super) struct CorSource {
    /// CoR centres as combinations of rest vertices (`#V × #V` sparse), when loaded: Λ = S·Φ.
    pub(super) rows: Option<SparseRows>,
    /// Λ given with the parts (used once, on the first switch to CoR).
    pub(super) given: Option<CageCoords>,
    /// How Λ is computed when neither is given.
    pub(super) options: CorCentresOptions,
}

/// The skinning method in use, with its data.
#[derive(Debug, Clone)]
pub(super) enum ActiveSkinning {
    /// Linear blend skinning (Eq. 1).
    Lbs,
    /// Dual quaternion skinning.
    Dqs,
    /// Optimised centres of rotation (Le & Hodgins), centres Λ·C (Eq. 14).
    Cor(Box<CorState>),
    /// `(1 − b)·LBS + b·DQS` with the rig's DQ blend weights b.
    Blended(Box<BlendedSkinning>),
    /// A method from outside the library, bound to the rig.
    External(Arc<dyn BoundSkinning>),
}

/// The kernels of Ω every rig has (`#V × #J`).
#[derive(Debug, Clone)]
struct SkinningKernels {
    lbs: LinearBlendSkinning,
    dqs: DualQuaternionSkinning,
}

impl SkinningKernels {
    /// M' (`out`, `#V`) of `rest_mesh` (`#V`) under the skinning transforms `posed_from_rest`
    /// (`#J`) by the method `active`, with the given scratch.
    fn apply(
        &self,
        active: &ActiveSkinning,
        posed_from_rest: &[DAffine3],
        rest_mesh: &[DVec3],
        dqs_scratch: &mut DqsScratch,
        cor_scratch: &mut CorScratch,
        out: &mut [DVec3],
    ) {
        match active {
            ActiveSkinning::Lbs => self.lbs.apply(posed_from_rest, rest_mesh, out),
            ActiveSkinning::Dqs => self.dqs.apply(posed_from_rest, rest_mesh, dqs_scratch, out),
            ActiveSkinning::Blended(blended) => {
                blended.apply(posed_from_rest, rest_mesh, dqs_scratch, out)
            }
            ActiveSkinning::Cor(cor) => {
                cor.skinning
                    .apply(posed_from_rest, rest_mesh, &cor.centres, cor_scratch, out)
            }
            ActiveSkinning::External(bound) => bound.apply(posed_from_rest, rest_mesh, out),
        }
    }
}

/// The skinning component: the kernels, the method in use and the data of the others.
#[derive(Debug, Clone)]
pub(super) struct RigSkinning {
    kernels: SkinningKernels,
    dqs_scratch: DqsScratch,
    cor_scratch: CorScratch,
    active: ActiveSkinning,
    /// The CoR state while another method is active (once built).
    idle_cor: Option<Box<CorState>>,
    /// The blended kernel while another method is active (`None` when the rig has no b, or
    /// while it is active).
    idle_blended: Option<Box<BlendedSkinning>>,
    /// The external method while another method is active (`None` when the session has none,
    /// or while it is active).
    idle_external: Option<Arc<dyn BoundSkinning>>,
    /// Where Λ comes from on the first switch to CoR.
    cor_source: CorSource,
}

impl RigSkinning {
    /// LBS with the kernels of Ω `skin_weights` (`#V × #J`), the rig's blended kernel when it
    /// has DQ blend weights, the external method bound to the rig when one was passed in, and
    /// where CoR's Λ will come from.
    pub(super) fn new(
        skin_weights: &SkinWeights,
        blended: Option<BlendedSkinning>,
        external: Option<Arc<dyn BoundSkinning>>,
        cor_source: CorSource,
    ) -> Self {
        Self {
            kernels: SkinningKernels {
                lbs: LinearBlendSkinning::new(skin_weights),
                dqs: DualQuaternionSkinning::new(skin_weights),
            },
            dqs_scratch: DqsScratch::new(skin_weights.num_joints()),
            cor_scratch: CorScratch::new(skin_weights.num_joints()),
            active: ActiveSkinning::Lbs,
            idle_cor: None,
            idle_blended: blended.map(Box::new),
            idle_external: external,
            cor_source,
        }
    }

    /// The method in use.
    pub(super) fn method(&self) -> SkinningMethod {
        match self.active {
            ActiveSkinning::Lbs => SkinningMethod::Lbs,
            ActiveSkinning::Dqs => SkinningMethod::Dqs,
            ActiveSkinning::Cor(_) => SkinningMethod::Cor,
            ActiveSkinning::Blended(_) => SkinningMethod::Blended,
            ActiveSkinning::External(_) => SkinningMethod::External,
        }
    }

    /// The method in use, with its data.
    pub(super) fn active(&self) -> &ActiveSkinning {
        &self.active
    }

    /// The LBS kernel of Ω.
    pub(super) fn lbs(&self) -> &LinearBlendSkinning {
        &self.kernels.lbs
    }

    /// The rig's DQ blend weights b (`#V`), when it has them.
    pub(super) fn dq_blend_weights(&self) -> Option<&DqBlendWeights> {
        match &self.active {
            ActiveSkinning::Blended(blended) => Some(blended.dq_blend_weights()),
            ActiveSkinning::Lbs
            | ActiveSkinning::Dqs
            | ActiveSkinning::Cor(_)
            | ActiveSkinning::External(_) => self
                .idle_blended
                .as_deref()
                .map(BlendedSkinning::dq_blend_weights),
        }
    }

    /// The CoR state, active or idle, once built.
    pub(super) fn cor(&self) -> Option<&CorState> {
        match &self.active {
            ActiveSkinning::Cor(cor) => Some(cor),
            ActiveSkinning::Lbs
            | ActiveSkinning::Dqs
            | ActiveSkinning::Blended(_)
            | ActiveSkinning::External(_) => self.idle_cor.as_deref(),
        }
    }

    /// Whether the CoR state has been built.
    pub(super) fn has_cor(&self) -> bool {
        self.cor().is_some()
    }

    /// Whether the session has an external method (active or idle).
    fn has_external(&self) -> bool {
        matches!(self.active, ActiveSkinning::External(_)) || self.idle_external.is_some()
    }

    /// Selects `method`. CoR needs its state built first ([`RigSkinning::build_cor`]); Blended
    /// needs the rig's DQ blend weights ([`RigError::NoDqBlendWeights`]); External a method
    /// passed in ([`RigError::NoExternalSkinning`]). Nothing changes on error.
    pub(super) fn select(&mut self, method: SkinningMethod) -> Result<(), RigError> {
        match method {
            SkinningMethod::Blended if self.dq_blend_weights().is_none() => {
                return Err(RigError::NoDqBlendWeights);
            }
            SkinningMethod::Cor if !self.has_cor() => {
                return Err(RigError::Invalid(
                    "CoR skinning was selected before its centres were built".into(),
                ));
            }
            SkinningMethod::External if !self.has_external() => {
                return Err(RigError::NoExternalSkinning);
            }
            SkinningMethod::Lbs
            | SkinningMethod::Dqs
            | SkinningMethod::Cor
            | SkinningMethod::Blended
            | SkinningMethod::External => {}
        }
        if method == self.method() {
            return Ok(());
        }
        self.park_active();
        // Checked above: the data of `method` is idle here.
        self.active = match method {
            SkinningMethod::Lbs => ActiveSkinning::Lbs,
            SkinningMethod::Dqs => ActiveSkinning::Dqs,
            SkinningMethod::Cor => match self.idle_cor.take() {
                Some(cor) => ActiveSkinning::Cor(cor),
                None => ActiveSkinning::Lbs,
            },
            SkinningMethod::Blended => match self.idle_blended.take() {
                Some(blended) => ActiveSkinning::Blended(blended),
                None => ActiveSkinning::Lbs,
            },
            SkinningMethod::External => match self.idle_external.take() {
                Some(external) => ActiveSkinning::External(external),
                None => ActiveSkinning::Lbs,
            },
        };
        Ok(())
    }

    /// Selects `method` again after a refused event. Its data was built before the event and
    /// is kept, so this cannot fail; were it to, LBS (the ghost fit's consensus) is the defined
    /// result.
    pub(super) fn restore(&mut self, method: SkinningMethod) {
        if self.select(method).is_err() {
            self.park_active();
        }
    }

    /// LBS becomes the method in use; the data of the one that was is kept idle.
    fn park_active(&mut self) {
        match std::mem::replace(&mut self.active, ActiveSkinning::Lbs) {
            ActiveSkinning::Lbs | ActiveSkinning::Dqs => {}
            ActiveSkinning::Cor(cor) => self.idle_cor = Some(cor),
            ActiveSkinning::Blended(blended) => self.idle_blended = Some(blended),
            ActiveSkinning::External(external) => self.idle_external = Some(external),
        }
    }

    /// Builds the CoR state with `build` (given where Λ comes from), unless it is built.
    pub(super) fn build_cor(
        &mut self,
        build: impl FnOnce(&mut CorSource) -> Result<CorState, RigError>,
    ) -> Result<(), RigError> {
        if !self.has_cor() {
            self.idle_cor = Some(Box::new(build(&mut self.cor_source)?));
        }
        Ok(())
    }

    /// After C changed everywhere: the active CoR's centres from `centres_of` (Λ·C and the
    /// coordinates kind's terms); an idle CoR's are marked stale.
    pub(super) fn centres_follow_cage(
        &mut self,
        centres_of: impl FnOnce(&CageCoords, &mut [DVec3]),
    ) {
        match &mut self.active {
            ActiveSkinning::Cor(cor) => centres_of(&cor.centre_coords, &mut cor.centres),
            ActiveSkinning::Lbs
            | ActiveSkinning::Dqs
            | ActiveSkinning::Blended(_)
            | ActiveSkinning::External(_) => self.mark_idle_centres_stale(),
        }
    }

    /// After the rest-cage vertices `vertices` moved by `deltas`: the active CoR's centres
    /// += Λ[:, k]·ΔC_k when they are current and the map is `linear`; otherwise (and for an
    /// idle CoR) they are marked stale.
    pub(super) fn centres_follow_cage_delta(
        &mut self,
        vertices: &[usize],
        deltas: &[DVec3],
        linear: bool,
    ) {
        match &mut self.active {
            ActiveSkinning::Cor(cor) if !cor.stale && linear => {
                cor.centre_coords
                    .apply_delta(vertices, deltas, &mut cor.centres)
            }
            ActiveSkinning::Cor(cor) => cor.stale = true,
            ActiveSkinning::Lbs
            | ActiveSkinning::Dqs
            | ActiveSkinning::Blended(_)
            | ActiveSkinning::External(_) => self.mark_idle_centres_stale(),
        }
    }

    /// Between two cage keyframes of a linear map: the active CoR's centres become
    /// `blend(centres)` when both keys carry centres (`blend` is `None` otherwise); they are
    /// marked stale otherwise, and for an idle CoR.
    pub(super) fn centres_follow_keyframes(&mut self, blend: Option<impl FnOnce(&mut [DVec3])>) {
        match (&mut self.active, blend) {
            (ActiveSkinning::Cor(cor), Some(blend)) => {
                blend(&mut cor.centres);
                cor.stale = false;
            }
            (ActiveSkinning::Cor(cor), None) => cor.stale = true,
            (
                ActiveSkinning::Lbs
                | ActiveSkinning::Dqs
                | ActiveSkinning::Blended(_)
                | ActiveSkinning::External(_),
                _,
            ) => self.mark_idle_centres_stale(),
        }
    }

    /// Before skinning: an active CoR whose centres lag behind C gets them from `centres_of`.
    pub(super) fn refresh_stale_centres(
        &mut self,
        centres_of: impl FnOnce(&CageCoords, &mut [DVec3]),
    ) {
        if let ActiveSkinning::Cor(cor) = &mut self.active
            && cor.stale
        {
            centres_of(&cor.centre_coords, &mut cor.centres);
            cor.stale = false;
        }
    }

    fn mark_idle_centres_stale(&mut self) {
        if let Some(cor) = &mut self.idle_cor {
            cor.stale = true;
        }
    }

    /// M' (`out`, `#V`) of the rest mesh `rest_mesh` (`#V`) under the skinning transforms
    /// `posed_from_rest` (`#J`), with the component's own scratch.
    pub(super) fn apply(
        &mut self,
        posed_from_rest: &[DAffine3],
        rest_mesh: &[DVec3],
        out: &mut [DVec3],
    ) {
        let Self {
            kernels,
            dqs_scratch,
            cor_scratch,
            active,
            ..
        } = self;
        kernels.apply(
            active,
            posed_from_rest,
            rest_mesh,
            dqs_scratch,
            cor_scratch,
            out,
        );
    }

    /// [`RigSkinning::apply`] with caller-owned scratch (for a lazily computed M' behind `&`).
    pub(super) fn apply_with(
        &self,
        posed_from_rest: &[DAffine3],
        rest_mesh: &[DVec3],
        dqs_scratch: &mut DqsScratch,
        cor_scratch: &mut CorScratch,
        out: &mut [DVec3],
    ) {
        self.kernels.apply(
            &self.active,
            posed_from_rest,
            rest_mesh,
            dqs_scratch,
            cor_scratch,
            out,
        );
    }
}
