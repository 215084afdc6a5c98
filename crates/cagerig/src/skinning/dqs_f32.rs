//! Dual quaternion skinning in f32 for per-frame display (Eq. 4; same rules as
//! [`super::dqs`]: sign alignment with the heaviest influence, rotation polar factors of non-rigid
//! `T_j^r`), evaluated with SSE-width glam `Quat`/`Vec3A` arithmetic.
//!
//! The rest mesh M is **stored** in the kernel (f32 offsets from a local origin `o`): call
//! [`DqsF32::set_rest_positions`] after a rest-cage edit. The joint dual quaternions are those of
//! `T_j ∘ translate(o)`, built in f64 and rounded (DQS blending commutes with that right factor).
//! Accuracy vs [`super::DualQuaternionSkinning`]: max |f32 − f64| is 4.8e-7 of the bbox diagonal
//! on the 3× subdivided Arm at step ii (tests assert ≤ 2e-6).

use glam::{DAffine3, DVec3, Quat, Vec3, Vec3A};

use super::compact_weights::{SortedRestMesh, VertexKernel};
use super::dqs::DualQuat;
use crate::{RigError, SkinWeights};

/// A unit dual quaternion `real + ε dual` in f32.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualQuatF32 {
    pub real: Quat,
    pub dual: Quat,
}

impl DualQuatF32 {
    pub const IDENTITY: Self = Self {
        real: Quat::IDENTITY,
        dual: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
    };
}

/// Caller-owned per-frame buffer: the `#J` joint dual quaternions of `T_j ∘ translate(o)`.
#[derive(Debug, Clone)]
pub struct DqsF32Scratch {
    joint_dual_quats: Vec<DualQuatF32>,
}

impl DqsF32Scratch {
    pub fn new(num_joints: usize) -> Self {
        Self {
            joint_dual_quats: vec![DualQuatF32::IDENTITY; num_joints],
        }
    }
}

/// Precomputed f32 DQS: compact Ω, pivots and the rest mesh M (`#V`, f32, local origin).
#[derive(Debug, Clone)]
pub struct DqsF32 {
    mesh: SortedRestMesh,
}

/// Per-frame DQS rule: input = local rest position `v − o`.
struct DqsKernel<'a> {
    joint_dual_quats: &'a [DualQuatF32],
    origin: Vec3A,
}

impl VertexKernel for DqsKernel<'_> {
    type Input = Vec3A;

    #[inline(always)]
    fn skin(&self, joints: &[u16], weights: &[f32], pivot: u16, rest: Vec3A) -> Vec3A {
        skin_point(
            joints,
            weights,
            usize::from(pivot),
            self.joint_dual_quats,
            rest,
        )
    }

    #[inline(always)]
    fn unweighted(&self, rest: Vec3A) -> Vec3A {
        rest + self.origin
    }
}

/// Sign-aligned normalised blend of one vertex applied to `p`: `R p + 2 (d r*)_xyz`.
#[inline(always)]
fn skin_point(
    joints: &[u16],
    weights: &[f32],
    pivot: usize,
    joint_dual_quats: &[DualQuatF32],
    p: Vec3A,
) -> Vec3A {
    let pivot_real = joint_dual_quats[pivot].real;
    let mut real = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    let mut dual = real;
    for (&j, &w) in joints.iter().zip(weights) {
        let q = &joint_dual_quats[usize::from(j)];
        let signed = w.copysign(pivot_real.dot(q.real));
        real += q.real * signed;
        dual += q.dual * signed;
    }
    // Unnormalised form: with n = |real|², R p = ((w² − v·v) p + 2 (v·p) v + 2 w v×p) / n and
    // t = 2 (w d_v − d_w v + v × d_v) / n (one division, no square root).
    let (v, w) = (Vec3A::new(real.x, real.y, real.z), real.w);
    let (dv, dw) = (Vec3A::new(dual.x, dual.y, dual.z), dual.w);
    let rotated = rotate_unnormalised(v, w, p);
    let translation = (dv * w - v * dw + v.cross(dv)) * 2.0;
    (rotated + translation) * (1.0 / (v.length_squared() + w * w))
}

/// `|q|² R(q) p` for a quaternion `q = (v, w)` of any non-zero length (R(q) the rotation of
/// `q / |q|`): `(w² − v·v) p + 2 (v·p) v + 2 w v × p`.
#[inline(always)]
pub(crate) fn rotate_unnormalised(v: Vec3A, w: f32, p: Vec3A) -> Vec3A {
    p * (w * w - v.length_squared()) + v * (2.0 * v.dot(p)) + v.cross(p) * (2.0 * w)
}

impl DqsF32 {
    /// Ω (`#V × #J`) and rest positions M (`#V`). Errors if the sizes differ or `#J` > 65 536.
    pub fn new(skin_weights: &SkinWeights, rest_positions: &[DVec3]) -> Result<Self, RigError> {
        Ok(Self {
            mesh: SortedRestMesh::new(
                skin_weights,
                rest_positions,
                "DQS f32 rest positions vs. weight rows",
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

    /// Fills `scratch` with the dual quaternions of `T_j ∘ translate(o)` (`#J`, f64 → f32).
    pub fn prepare(&self, transforms: &[DAffine3], scratch: &mut DqsF32Scratch) {
        assert_eq!(transforms.len(), self.num_joints(), "DQS f32: transforms");
        assert_eq!(
            scratch.joint_dual_quats.len(),
            self.num_joints(),
            "DQS f32: scratch"
        );
        let to_local = DAffine3::from_translation(self.mesh.origin);
        for (q, t) in scratch.joint_dual_quats.iter_mut().zip(transforms) {
            let dq = DualQuat::from_affine(&(*t * to_local));
            *q = DualQuatF32 {
                real: dq.real.as_quat(),
                dual: dq.dual.as_quat(),
            };
        }
    }

    /// M' = DQS(T, Ω, M) in f32 (Eq. 4). `transforms`: `#J`; `scratch`:
    /// `DqsF32Scratch::new(#J)`; `out`: `#V`. Unweighted vertices stay at rest.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(&self, transforms: &[DAffine3], scratch: &mut DqsF32Scratch, out: &mut [Vec3]) {
        self.prepare(transforms, scratch);
        let kernel = DqsKernel {
            joint_dual_quats: &scratch.joint_dual_quats,
            origin: Vec3A::from(self.mesh.origin.as_vec3()),
        };
        self.mesh.weights.skin(&kernel, &self.mesh.rest_local, out);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn skin(weights: &[Vec<f64>], transforms: &[DAffine3], rest: &[DVec3]) -> Vec<Vec3> {
        let (w, _) = SkinWeights::from_dense(weights).unwrap();
        let dqs = DqsF32::new(&w, rest).unwrap();
        let mut out = vec![Vec3::ZERO; rest.len()];
        dqs.apply(
            transforms,
            &mut DqsF32Scratch::new(transforms.len()),
            &mut out,
        );
        out
    }

    #[test]
    fn single_bone_rotation_about_a_point() {
        let pivot = DVec3::new(1.0, 2.0, 0.0);
        let t = DAffine3::from_translation(pivot)
            * DAffine3::from_rotation_z(FRAC_PI_2)
            * DAffine3::from_translation(-pivot);
        let out = skin(&[vec![1.0]], &[t], &[DVec3::new(2.0, 2.0, 5.0)]);
        assert!(
            out[0].abs_diff_eq(Vec3::new(1.0, 3.0, 5.0), 1e-6),
            "{out:?}"
        );
    }

    #[test]
    fn half_half_twist_preserves_the_point_and_opposite_rotations_blend_through_180() {
        let t = [
            DAffine3::from_rotation_x(FRAC_PI_2),
            DAffine3::from_rotation_x(-FRAC_PI_2),
        ];
        let p = DVec3::new(3.0, 1.0, 2.0);
        let out = skin(&[vec![0.5, 0.5]], &t, &[p]);
        assert!(out[0].abs_diff_eq(p.as_vec3(), 1e-6), "{out:?}");
        let t = [
            DAffine3::from_rotation_z(170f64.to_radians()),
            DAffine3::from_rotation_z(-170f64.to_radians()),
        ];
        let out = skin(&[vec![0.5, 0.5]], &t, &[DVec3::X]);
        assert!(out[0].abs_diff_eq(-Vec3::X, 1e-6), "{out:?}");
    }
}
