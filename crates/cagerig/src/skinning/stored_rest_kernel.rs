//! What every f32 display kernel that stores the rest mesh M shares: the count-sorted Ω with M
//! beside it as f32 offsets from a local origin ([`SortedRestMesh`]), its sizes, and the refresh
//! after a rest-cage edit, and the constructor of the methods without data of their own
//! ([`RestOnlyMethod`]). Each method adds its own data `M` and its `apply` (and its `new` when it
//! has data)
//! ([`super::LbsF32`], [`super::DqsF32`], [`super::BlendedF32`]; CoR also stores its centres and
//! keeps its own type, [`super::CorF32`]).

use super::compact_weights::SortedRestMesh;
use super::precision::RestPoint;
use crate::{RigError, SkinWeights};

/// An f32 kernel of the method `M` over a stored rest mesh M (`#V`, f32, sorted order).
#[derive(Debug, Clone)]
pub struct StoredRestKernel<M> {
    pub(super) mesh: SortedRestMesh,
    pub(super) method: M,
}

impl<M> StoredRestKernel<M> {
    /// Ω (`#V × #J`), rest positions M (`#V`) and the method's data. `what` names the kernel
    /// when the sizes differ.
    pub(super) fn build<P: RestPoint>(
        skin_weights: &SkinWeights,
        rest_positions: &[P],
        what: &'static str,
        method: M,
    ) -> Result<Self, RigError> {
        Ok(Self {
            mesh: SortedRestMesh::new(skin_weights, rest_positions, what)?,
            method,
        })
    }

    /// Number of mesh vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.mesh.weights.num_vertices()
    }

    /// Number of joints `#J`.
    pub fn num_joints(&self) -> usize {
        self.mesh.weights.num_joints
    }

    /// Replaces the stored rest mesh M (`#V`; after a rest-cage edit). Parallel, no allocation.
    pub fn set_rest_positions<P: RestPoint>(
        &mut self,
        rest_positions: &[P],
    ) -> Result<(), RigError> {
        self.mesh.set_rest_positions(rest_positions)
    }
}

/// A method with no data beyond Ω and M ([`super::LbsF32Method`], [`super::DqsF32Method`]):
/// its kernel is built from those two alone.
pub trait RestOnlyMethod: Sized {
    /// The method's value.
    const METHOD: Self;
    /// Names the kernel when the sizes of Ω and M differ.
    const SIZE_MISMATCH: &'static str;
}

impl<M: RestOnlyMethod> StoredRestKernel<M> {
    /// Ω (`#V × #J`) and rest positions M (`#V`). Errors if the sizes differ.
    pub fn new<P: RestPoint>(
        skin_weights: &SkinWeights,
        rest_positions: &[P],
    ) -> Result<Self, RigError> {
        Self::build(skin_weights, rest_positions, M::SIZE_MISMATCH, M::METHOD)
    }
}
