//! Linear blend skinning in f32 for per-frame display (Eq. 2–3):
//! `v'_i = (Σ_j ω_ij T_j) v_i`, evaluated with SSE-width glam `Affine3A`/`Vec3A` arithmetic.
//!
//! The rest mesh M is **stored** in the kernel (as f32 offsets from a local origin, see
//! [`super::compact_weights`]): call [`LbsF32::set_rest_positions`] whenever the rest cage is
//! edited. Accuracy: on the 3× subdivided Arm at step ii max |f32 − f64| is 3.1e-7
//! of the bounding-box diagonal vs [`super::LinearBlendSkinning`] (tests assert ≤ 2e-6); use the f64 kernel where exact
//! results are needed (conformance, CageRev/CageUp solves).

use glam::{Affine3A, DAffine3, DVec3, Vec3, Vec3A};

use super::compact_weights::{SortedRestMesh, VertexKernel, affine_from_local};
use crate::{RigError, SkinWeights};

/// Caller-owned per-frame buffer: the `#J` transforms `T_j ∘ translate(o)` in f32.
#[derive(Debug, Clone)]
pub struct LbsF32Scratch {
    transforms: Vec<Affine3A>,
}

impl LbsF32Scratch {
    pub fn new(num_joints: usize) -> Self {
        Self {
            transforms: vec![Affine3A::IDENTITY; num_joints],
        }
    }
}

/// Precomputed f32 LBS: count-sorted compact Ω and the rest mesh M (`#V`, f32, relative to a
/// local origin, in sorted order; see [`super::compact_weights`]).
#[derive(Debug, Clone)]
pub struct LbsF32 {
    mesh: SortedRestMesh,
}

/// `Σ_j ω_j A_j` for the influences of one vertex (`A_j` local-to-world, f32).
#[inline(always)]
pub(crate) fn blend_affine_f32(
    joints: &[u16],
    weights: &[f32],
    transforms: &[Affine3A],
) -> Affine3A {
    let mut x = Vec3A::ZERO;
    let mut y = Vec3A::ZERO;
    let mut z = Vec3A::ZERO;
    let mut t = Vec3A::ZERO;
    for (&j, &w) in joints.iter().zip(weights) {
        let a = &transforms[usize::from(j)];
        x += a.matrix3.x_axis * w;
        y += a.matrix3.y_axis * w;
        z += a.matrix3.z_axis * w;
        t += a.translation * w;
    }
    Affine3A {
        matrix3: glam::Mat3A::from_cols(x, y, z),
        translation: t,
    }
}

/// Per-frame LBS rule: input = local rest position `v − o`.
struct LbsKernel<'a> {
    transforms: &'a [Affine3A],
    origin: Vec3A,
}

impl VertexKernel for LbsKernel<'_> {
    type Input = Vec3A;

    #[inline(always)]
    fn skin(&self, joints: &[u16], weights: &[f32], _pivot: u16, rest: Vec3A) -> Vec3A {
        blend_affine_f32(joints, weights, self.transforms).transform_point3a(rest)
    }

    #[inline(always)]
    fn unweighted(&self, rest: Vec3A) -> Vec3A {
        rest + self.origin
    }
}

impl LbsF32 {
    /// Ω (`#V × #J`) and rest positions M (`#V`). Errors if the sizes differ or `#J` > 65 536.
    pub fn new(skin_weights: &SkinWeights, rest_positions: &[DVec3]) -> Result<Self, RigError> {
        Ok(Self {
            mesh: SortedRestMesh::new(
                skin_weights,
                rest_positions,
                "LBS f32 rest positions vs. weight rows",
            )?,
        })
    }

    pub fn num_vertices(&self) -> usize {
        self.mesh.weights.num_vertices()
    }

    pub fn num_joints(&self) -> usize {
        self.mesh.weights.num_joints
    }

    /// Replaces the stored rest mesh M (`#V`; after a rest-cage edit). Parallel, no allocation.
    pub fn set_rest_positions(&mut self, rest_positions: &[DVec3]) -> Result<(), RigError> {
        self.mesh.set_rest_positions(rest_positions)
    }

    /// Fills `scratch` with `T_j ∘ translate(o)` in f32 (`#J`, serial).
    pub fn prepare(&self, transforms: &[DAffine3], scratch: &mut LbsF32Scratch) {
        assert_eq!(transforms.len(), self.num_joints(), "LBS f32: transforms");
        assert_eq!(
            scratch.transforms.len(),
            self.num_joints(),
            "LBS f32: scratch"
        );
        for (a, t) in scratch.transforms.iter_mut().zip(transforms) {
            *a = affine_from_local(t, self.mesh.origin);
        }
    }

    /// M' = LBS(T, Ω, M) in f32 (Eq. 2–3). `transforms`: `#J`; `scratch`:
    /// `LbsF32Scratch::new(#J)`; `out`: `#V`. Unweighted vertices stay at rest.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(&self, transforms: &[DAffine3], scratch: &mut LbsF32Scratch, out: &mut [Vec3]) {
        self.prepare(transforms, scratch);
        let kernel = LbsKernel {
            transforms: &scratch.transforms,
            origin: Vec3A::from(self.mesh.origin.as_vec3()),
        };
        self.mesh.weights.skin(&kernel, &self.mesh.rest_local, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
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
