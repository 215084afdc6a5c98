//! Linear blend skinning in f32 for per-frame display (Eq. 2–3):
//! `v'_i = (Σ_j ω_ij T_j) v_i`, evaluated with SSE-width glam `Affine3A`/`Vec3A` arithmetic.
//!
//! The rest mesh M is **stored** in the kernel (as f32 offsets from a local origin, see
//! [`super::compact_weights`]): call [`LbsF32::set_rest_positions`] whenever the rest cage is
//! edited. Accuracy: on the 3× subdivided Arm at step ii max |f32 − f64| is 3.1e-7
//! of the bounding-box diagonal vs [`super::LinearBlendSkinning`] (tests assert ≤ 2e-6); use the f64 kernel where exact
//! results are needed (conformance, CageRev/CageUp solves).

use glam::{DAffine3, Vec3, Vec3A};

use super::compact_weights::columns_from_local;
use super::lbs::LbsRule;
use super::stored_rest_kernel::{RestOnlyMethod, StoredRestKernel};

/// Caller-owned per-frame buffer: the `#J` transforms `T_j ∘ translate(o)` as f32 columns.
#[derive(Debug, Clone)]
pub struct LbsF32Scratch {
    columns: Vec<[Vec3A; 4]>,
}

impl LbsF32Scratch {
    /// A buffer for `num_joints` (`#J`) joints, initialised to identities.
    pub fn new(num_joints: usize) -> Self {
        Self {
            columns: vec![[Vec3A::X, Vec3A::Y, Vec3A::Z, Vec3A::ZERO]; num_joints],
        }
    }
}

/// The method data of [`LbsF32`]: none beyond Ω and M.
#[derive(Debug, Clone, Copy)]
pub struct LbsF32Method;

/// Precomputed f32 LBS: count-sorted compact Ω and the rest mesh M (`#V`, f32, relative to a
/// local origin, in sorted order; see [`super::compact_weights`]).
pub type LbsF32 = StoredRestKernel<LbsF32Method>;

impl RestOnlyMethod for LbsF32Method {
    const METHOD: Self = LbsF32Method;
    const SIZE_MISMATCH: &'static str = "LBS f32 rest positions vs. weight rows";
}

impl LbsF32 {
    /// M' = LBS(T, Ω, M) in f32 (Eq. 2–3). `transforms`: `#J`; `scratch`:
    /// `LbsF32Scratch::new(#J)`; `out`: `#V`. Unweighted vertices stay at rest.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(&self, transforms: &[DAffine3], scratch: &mut LbsF32Scratch, out: &mut [Vec3]) {
        assert_eq!(transforms.len(), self.num_joints(), "LBS f32: transforms");
        columns_from_local::<f32>(transforms, self.mesh.origin, &mut scratch.columns);
        let rule = LbsRule {
            transforms: &scratch.columns[..],
            points: self.mesh.points(),
        };
        self.mesh.weights.skin(&rule, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::SkinWeights;
    use glam::DVec3;
    use std::f64::consts::FRAC_PI_2;

    #[test]
    fn single_bone_rotation_about_a_point_and_unweighted_vertex() {
        let (w, _) = SkinWeights::from_triplets(3, 1, [(0, 0, 1.0), (1, 0, 1.0)]).unwrap();
        let pivot = DVec3::new(101.0, 0.0, 0.0);
        let about_pivot = DAffine3::from_translation(pivot)
            * DAffine3::from_rotation_z(FRAC_PI_2)
            * DAffine3::from_translation(-pivot);
        let t = [about_pivot];
        let rest = [
            DVec3::new(102.0, 0.0, 0.0),
            DVec3::new(101.0, 0.0, 3.0),
            DVec3::new(7.0, 8.0, 9.0),
        ];
        let lbs = LbsF32::new(&w, &rest).unwrap();
        let mut out = [Vec3::ZERO; 3];
        lbs.apply(&t, &mut LbsF32Scratch::new(1), &mut out);
        assert!(
            out[0].abs_diff_eq(Vec3::new(101.0, 1.0, 0.0), 2e-5),
            "{out:?}"
        );
        assert!(
            out[1].abs_diff_eq(Vec3::new(101.0, 0.0, 3.0), 2e-5),
            "{out:?}"
        );
        assert!(
            out[2].abs_diff_eq(Vec3::new(7.0, 8.0, 9.0), 2e-5),
            "{out:?}"
        );
    }

    #[test]
    fn half_half_plus_minus_90_degrees_collapses() {
        let (w, _) = SkinWeights::from_dense(&[vec![0.5, 0.5]]).unwrap();
        let lbs = LbsF32::new(&w, &[DVec3::new(3.0, 1.0, 2.0)]).unwrap();
        let t = [
            DAffine3::from_rotation_x(FRAC_PI_2),
            DAffine3::from_rotation_x(-FRAC_PI_2),
        ];
        let mut out = [Vec3::ZERO];
        lbs.apply(&t, &mut LbsF32Scratch::new(2), &mut out);
        assert!(
            out[0].abs_diff_eq(Vec3::new(3.0, 0.0, 0.0), 1e-6),
            "{out:?}"
        );
    }
}
