//! Optimized centres-of-rotation skinning in f32 for per-frame display (Eq. 6; the f32 instance
//! of the rule of [`super::cor`]): `v'_i = R(i) (v_i − p_i) + Σ_j ω_ij T_j p_i`, with `R(i)` the normalised
//! sign-aligned quaternion blend, evaluated with SSE-width glam `Affine3A`/`Quat`/`Vec3A`.
//!
//! The rest mesh M and the centres p_i are **stored** in the kernel, as f32 values of
//! `p_i − o` (local origin `o`) and `v_i − p_i` (differences taken in f64): call
//! [`CorF32::set_rest_positions`] with both after a rest-cage edit (the centres follow the cage,
//! CoRs = Λ·C, Eq. 14). A non-finite centre means "no CoR": the vertex is skinned by LBS, as in
//! the f64 kernel. Accuracy vs [`super::CorSkinning`]: max |f32 − f64| is 2.9e-7 of the bbox
//! diagonal on the 3× subdivided Arm at step ii (tests assert ≤ 2e-6).

use glam::{DAffine3, DVec3, Vec3, Vec3A};

use super::compact_weights::{CountSortedWeights, local_origin};
use super::cor::{CorScratch, LocalCentredPoints};
use super::precision::RestPoint;
use crate::{RigError, SkinWeights};

/// Caller-owned per-frame buffer: `T_j ∘ translate(o)` and the rotation quaternions, `#J`, f32.
pub type CorF32Scratch = CorScratch<f32>;

/// Precomputed f32 CoR skinning: compact Ω, pivots, centres `p_i − o` and offsets `v_i − p_i`.
#[derive(Debug, Clone)]
pub struct CorF32 {
    weights: CountSortedWeights<f32>,
    origin: DVec3,
    /// `[p_i − o, v_i − p_i]` (`[v_i − o, 0]` for a vertex without CoR), `#V`, sorted order.
    centres_and_offsets: Vec<[Vec3A; 2]>,
}

impl CorF32 {
    /// Ω (`#V × #J`), rest positions M and centres p_i (both `#V`, rest space). Errors if the
    /// sizes differ.
    pub fn new<P: RestPoint>(
        skin_weights: &SkinWeights,
        rest_positions: &[P],
        centres: &[DVec3],
    ) -> Result<Self, RigError> {
        let weights = CountSortedWeights::new(skin_weights);
        let mut cor = Self {
            centres_and_offsets: vec![[Vec3A::ZERO; 2]; weights.num_vertices()],
            weights,
            origin: DVec3::ZERO,
        };
        cor.set_rest_positions(rest_positions, centres)?;
        Ok(cor)
    }

    /// Number of mesh vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.weights.num_vertices()
    }

    /// Number of joints `#J`.
    pub fn num_joints(&self) -> usize {
        self.weights.num_joints
    }

    /// Replaces the stored rest mesh M and centres p_i (both `#V`; after a rest-cage edit).
    /// Parallel, no allocation.
    pub fn set_rest_positions<P: RestPoint>(
        &mut self,
        rest_positions: &[P],
        centres: &[DVec3],
    ) -> Result<(), RigError> {
        for (what, len) in [
            (
                "CoR f32 rest positions vs. weight rows",
                rest_positions.len(),
            ),
            ("CoR f32 centres vs. weight rows", centres.len()),
        ] {
            if len != self.num_vertices() {
                return Err(RigError::SizeMismatch {
                    what,
                    expected: self.num_vertices(),
                    actual: len,
                });
            }
        }
        self.origin = local_origin(rest_positions);
        let origin = self.origin;
        self.weights.gather(&mut self.centres_and_offsets, |i| {
            let v = rest_positions[i].to_f64();
            let c = if centres[i].is_finite() {
                centres[i]
            } else {
                v
            };
            [
                Vec3A::from((c - origin).as_vec3()),
                Vec3A::from((v - c).as_vec3()),
            ]
        });
        Ok(())
    }

    /// M' = CoR(T, Ω, M, P) in f32 (Eq. 6). `transforms`: `#J`; `scratch`:
    /// `CorF32Scratch::new(#J)`; `out`: `#V`. Unweighted vertices stay at rest.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(&self, transforms: &[DAffine3], scratch: &mut CorF32Scratch, out: &mut [Vec3]) {
        assert_eq!(transforms.len(), self.num_joints(), "CoR f32: transforms");
        scratch.skin(
            transforms,
            self.origin,
            &self.weights,
            LocalCentredPoints {
                stored: &self.centres_and_offsets,
                origin: Vec3A::from(self.origin.as_vec3()),
            },
            out,
        );
    }
}
