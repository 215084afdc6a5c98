//! Dual quaternion skinning in f32 for per-frame display (Eq. 4): the f32 instance of the rule of
//! [`super::dqs`] (sign alignment with the heaviest influence, rotation polar factors of non-rigid
//! `T_j^r`), evaluated with SSE-width glam `Quat`/`Vec3A` arithmetic.
//!
//! The rest mesh M is **stored** in the kernel (f32 offsets from a local origin `o`): call
//! [`DqsF32::set_rest_positions`] after a rest-cage edit. The joint dual quaternions are those of
//! `T_j ∘ translate(o)`, built in f64 and rounded (DQS blending commutes with that right factor).
//! Accuracy vs [`super::DualQuaternionSkinning`]: max |f32 − f64| is 4.8e-7 of the bbox diagonal
//! on the 3× subdivided Arm at step ii (tests assert ≤ 2e-6).

use glam::{DAffine3, Vec3};

use super::dqs::DqsScratch;
use super::stored_rest_kernel::{RestOnlyMethod, StoredRestKernel};

/// Caller-owned per-frame buffer: the `#J` joint dual quaternions of `T_j ∘ translate(o)`, f32.
pub type DqsF32Scratch = DqsScratch<f32>;

/// The method data of [`DqsF32`]: none beyond Ω, its pivots and M.
#[derive(Debug, Clone, Copy)]
pub struct DqsF32Method;

/// Precomputed f32 DQS: compact Ω, pivots and the rest mesh M (`#V`, f32, local origin).
pub type DqsF32 = StoredRestKernel<DqsF32Method>;

impl RestOnlyMethod for DqsF32Method {
    const METHOD: Self = DqsF32Method;
    const SIZE_MISMATCH: &'static str = "DQS f32 rest positions vs. weight rows";
}

impl DqsF32 {
    /// M' = DQS(T, Ω, M) in f32 (Eq. 4). `transforms`: `#J`; `scratch`:
    /// `DqsF32Scratch::new(#J)`; `out`: `#V`. Unweighted vertices stay at rest.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(&self, transforms: &[DAffine3], scratch: &mut DqsF32Scratch, out: &mut [Vec3]) {
        assert_eq!(transforms.len(), self.num_joints(), "DQS f32: transforms");
        scratch.skin(
            transforms,
            self.mesh.origin,
            &self.mesh.weights,
            self.mesh.points(),
            out,
        );
    }
}
