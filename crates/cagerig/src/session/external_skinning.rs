//! A skinning method from outside the library, passed in
//! [`super::SessionOptions::external_skinning`] and selected as
//! [`SkinningMethod::External`].
//!
//! A method is two traits, as the display path's rest map ([`super::DisplayRestMap`]):
//! [`SkinningBackend::bind`] precomputes once per binding (the session binds, rebinds and
//! re-skeletons with the same backend) and returns a [`BoundSkinning`], whose
//! [`BoundSkinning::apply`] skins M' from M under the skinning transforms T_j = S'·S⁻¹ into the
//! session's buffer, per event.
//!
//! CageUp needs nothing of the method. By the session's one rule
//! ([`SkinningMethod::is_linear`]), only LBS is fitted directly: under every other method,
//! an external one included, CageUp fits the LBS "ghost" of its fitting rows (Sec. 4.3,
//! [`super::CageFitSource::GhostLbs`], the default), so the loop C' → C → S → S' → C' and
//! CageRev stay exact whatever the method draws. With
//! [`super::CageFitSource::DisplayedMesh`] CageUp reads the method's M' on the fitting rows.
//!
//! On the f32 display path ([`super::DisplayPrecision::F32`]) an external method has no f32
//! kernel: the drawn M' is its f64 M' rounded. `crates/cagerig/tests/toy_skinning.rs` is a
//! complete method written outside the library this way.

use std::fmt;
use std::sync::Arc;

use glam::{DAffine3, DVec3};

use crate::skeleton::Skeleton;
use crate::skin_weights::SkinWeights;
#[cfg(doc)]
use crate::skinning::SkinningMethod;

/// What a method may precompute from, at binding: the rig as the session binds it.
#[derive(Debug, Clone, Copy)]
pub struct SkinningBindInput<'a> {
    /// The rest skin M (`#V`) at binding.
    pub rest_mesh: &'a [DVec3],
    /// The mesh's triangles (`#T`, indices into `rest_mesh`).
    pub triangles: &'a [[u32; 3]],
    /// The rest skeleton S (`#J` joints, their rest frames `rest_world_from_joint`).
    pub skeleton: &'a Skeleton,
    /// Ω (`#V × #J`).
    pub skin_weights: &'a SkinWeights,
}

/// A skinning method bound to one rig.
pub trait BoundSkinning: Send + Sync + fmt::Debug {
    /// M' into `out` (`#V`) of the rest skin `rest_mesh` (`#V`, the current M, which follows the
    /// rest cage C) under the skinning transforms `posed_from_rest` (`#J`, T_j = S'_j·S_j⁻¹).
    /// Called once per event on the session's buffer; it should not allocate.
    fn apply(&self, posed_from_rest: &[DAffine3], rest_mesh: &[DVec3], out: &mut [DVec3]);
}

/// A skinning method from outside the library: it binds to each rig the session builds.
pub trait SkinningBackend: Send + Sync + fmt::Debug {
    /// A short name for reports and errors ("rigid").
    fn name(&self) -> &str;

    /// The method bound to `rig` (its per-rig precomputation), or why it cannot bind this rig
    /// (the session then fails with [`crate::RigError::ExternalSkinning`]).
    fn bind(&self, rig: &SkinningBindInput<'_>) -> Result<Arc<dyn BoundSkinning>, String>;
}
