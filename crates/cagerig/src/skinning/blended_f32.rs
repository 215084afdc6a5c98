//! Blended LBS/DQS skinning in f32 for per-frame display: the f32 instance of the rule of
//! [`super::blended`] (`v' = (1 − b_v)·LBS(v) + b_v·DQS(v)`), with the LBS part of
//! [`super::LbsF32`] and the DQS part of [`super::DqsF32`] on one count-sorted layout.
//!
//! The rest mesh M is **stored** in the kernel (f32 offsets from a local origin `o`): call
//! [`BlendedF32::set_rest_positions`] after a rest-cage edit. Accuracy vs
//! [`super::BlendedSkinning`]: a convex blend of the two f32 parts, so within the larger of their
//! errors (max |f32 − f64| ≤ 2e-6 of the bbox diagonal, asserted by `tests/display_path.rs` on the
//! subdivided Arm with random blend weights).

use glam::{DAffine3, Vec3, Vec3A};

use super::blended::skin_blended;
use super::compact_weights::columns_from_local;
use super::dq_blend_weights::DqBlendWeights;
use super::dqs::DqsScratch;
use super::precision::RestPoint;
use super::stored_rest_kernel::StoredRestKernel;
use crate::{RigError, SkinWeights};

/// Caller-owned per-frame buffer: the `#J` joint dual quaternions and f32 columns of
/// `T_j ∘ translate(o)`.
#[derive(Debug, Clone)]
pub struct BlendedF32Scratch {
    dqs: DqsScratch<f32>,
    columns: Vec<[Vec3A; 4]>,
}

impl BlendedF32Scratch {
    /// A buffer for `num_joints` (`#J`) joints.
    pub fn new(num_joints: usize) -> Self {
        Self {
            dqs: DqsScratch::new(num_joints),
            columns: vec![[Vec3A::X, Vec3A::Y, Vec3A::Z, Vec3A::ZERO]; num_joints],
        }
    }
}

/// The method data of [`BlendedF32`]: the DQ blend weights `b` (`#V`, f32, by vertex).
#[derive(Debug, Clone)]
pub struct BlendedF32Method {
    blend: Vec<f32>,
}

/// Precomputed f32 blended skinning: compact Ω, pivots, the rest mesh M (`#V`, f32, local
/// origin) and the DQ blend weights `b`.
pub type BlendedF32 = StoredRestKernel<BlendedF32Method>;

impl BlendedF32 {
    /// Ω (`#V × #J`), `b` (`#V`) and rest positions M (`#V`). Errors if the sizes differ.
    pub fn new<P: RestPoint>(
        skin_weights: &SkinWeights,
        blend: &DqBlendWeights,
        rest_positions: &[P],
    ) -> Result<Self, RigError> {
        blend.check_vertices(skin_weights.num_vertices())?;
        Self::build(
            skin_weights,
            rest_positions,
            "blended f32 rest positions vs. weight rows",
            // b ∈ [0, 1]: 0 and 1 stay exact, so those vertices run one rule alone.
            BlendedF32Method {
                blend: blend.values().iter().map(|&b| b as f32).collect(),
            },
        )
    }

    /// M' = (1 − b)·LBS + b·DQS in f32. `transforms`: `#J`; `scratch`:
    /// `BlendedF32Scratch::new(#J)`; `out`: `#V`. Unweighted vertices stay at rest.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(
        &self,
        transforms: &[DAffine3],
        scratch: &mut BlendedF32Scratch,
        out: &mut [Vec3],
    ) {
        assert_eq!(
            transforms.len(),
            self.num_joints(),
            "blended f32: transforms"
        );
        columns_from_local::<f32>(transforms, self.mesh.origin, &mut scratch.columns);
        skin_blended::<f32, _, _>(
            &mut scratch.dqs,
            transforms,
            &scratch.columns[..],
            self.mesh.origin,
            &self.mesh.weights,
            &self.method.blend,
            self.mesh.points(),
            out,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn twist_blend_far_from_the_origin_matches_the_analytic_points() {
        // ±90° twists about an x-parallel axis through (0, 100, 100): LBS collapses onto the
        // axis, DQS keeps the point, b = ½ lands half-way.
        let axis = DVec3::new(0.0, 100.0, 100.0);
        let about = |a: f64| {
            DAffine3::from_translation(axis)
                * DAffine3::from_rotation_x(a)
                * DAffine3::from_translation(-axis)
        };
        let t = [about(FRAC_PI_2), about(-FRAC_PI_2)];
        let p = axis + DVec3::new(3.0, 1.0, 2.0);
        let (w, _) = SkinWeights::from_dense(&vec![vec![0.5, 0.5]; 3]).unwrap();
        let b = DqBlendWeights::new(vec![0.0, 0.5, 1.0]).unwrap();
        let kernel = BlendedF32::new(&w, &b, &[p; 3]).unwrap();
        let mut out = [Vec3::ZERO; 3];
        kernel.apply(&t, &mut BlendedF32Scratch::new(2), &mut out);
        let lbs = axis + DVec3::new(3.0, 0.0, 0.0);
        let expected = [lbs, (lbs + p) * 0.5, p];
        for (o, e) in out.iter().zip(expected) {
            assert!(o.abs_diff_eq(e.as_vec3(), 2e-5), "{out:?} vs {expected:?}");
        }
    }
}
