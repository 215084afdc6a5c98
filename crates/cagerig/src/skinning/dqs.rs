//! Dual quaternion skinning (Kavan et al. 2008; Eq. 4): `v'_i = DQBlend(T_i, Ω_i) v_i`.
//!
//! Per joint, `T_j` becomes a unit dual quaternion `q̂_j = r_j + ε d_j` with `d_j = ½ t_j r_j`.
//! Per vertex, terms are sign-aligned with the **heaviest** influence (antipodality pivot; the
//! reference tool uses the first listed joint, which can flip the blend when that joint has a tiny
//! weight), blended with Ω, divided by `|Σ ω r|` and applied as `v' = R v + t`,
//! `t = 2 (d r*)_xyz`.
//!
//! DQS handles rigid transforms only: a `T_j^r` that is not a rotation is replaced by its
//! rotation polar factor ([`super::rigid_rotation`]); scale/shear are dropped, `T_j^t` kept.

use glam::{DAffine3, DQuat, DVec3};
use rayon::prelude::*;

use super::VERTEX_GRAIN;
use super::pivoted_weights::PivotedWeights;
use super::rigid_rotation::rotation_quaternion;
use crate::SkinWeights;

/// A dual quaternion `real + ε dual`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualQuat {
    pub real: DQuat,
    pub dual: DQuat,
}

impl DualQuat {
    pub const IDENTITY: Self = Self {
        real: DQuat::IDENTITY,
        dual: DQuat::from_xyzw(0.0, 0.0, 0.0, 0.0),
    };

    /// Unit dual quaternion of the rigid part of `transform` (rotation polar factor, translation).
    pub fn from_affine(transform: &DAffine3) -> Self {
        let real = rotation_quaternion(transform.matrix3);
        Self::from_rotation_translation(real, transform.translation)
    }

    /// `real + ε ½ (translation, 0)·real` for a unit `real`.
    pub fn from_rotation_translation(real: DQuat, translation: DVec3) -> Self {
        let t = DQuat::from_xyzw(translation.x, translation.y, translation.z, 0.0);
        Self {
            real,
            dual: (t * real) * 0.5,
        }
    }

    /// Translation `2 (dual · real*)_xyz` of a unit dual quaternion.
    #[inline(always)]
    pub fn translation(&self) -> DVec3 {
        (self.dual * self.real.conjugate()).xyz() * 2.0
    }

    /// Applies a unit dual quaternion to a point: `R p + t`.
    #[inline(always)]
    pub fn transform_point3(&self, p: DVec3) -> DVec3 {
        self.real.mul_vec3(p) + self.translation()
    }
}

/// Caller-owned per-frame buffer: the `#J` joint dual quaternions.
#[derive(Debug, Clone)]
pub struct DqsScratch {
    joint_dual_quats: Vec<DualQuat>,
}

impl DqsScratch {
    pub fn new(num_joints: usize) -> Self {
        Self {
            joint_dual_quats: vec![DualQuat::IDENTITY; num_joints],
        }
    }

    /// The joint dual quaternions of the last `apply`.
    pub fn joint_dual_quats(&self) -> &[DualQuat] {
        &self.joint_dual_quats
    }
}

/// Precomputed DQS: flat Ω (CSR) and the per-vertex pivot joint.
#[derive(Debug, Clone)]
pub struct DualQuaternionSkinning {
    csr: PivotedWeights,
}

/// Sign-aligned blend `Σ_j ω_j s_j q̂_j`, `s_j = sign(r_pivot · r_j)`, normalised by `|Σ ω s r|`.
#[inline(always)]
pub(crate) fn blend_dual_quats(
    joints: &[u32],
    weights: &[f64],
    pivot: usize,
    joint_dual_quats: &[DualQuat],
) -> DualQuat {
    let pivot_real = joint_dual_quats[pivot].real;
    let mut real = [0.0f64; 4];
    let mut dual = [0.0f64; 4];
    for (&j, &w) in joints.iter().zip(weights) {
        let q = &joint_dual_quats[j as usize];
        let signed = w.copysign(pivot_real.dot(q.real));
        for (sum, x) in real.iter_mut().zip(q.real.to_array()) {
            *sum += x * signed;
        }
        for (sum, x) in dual.iter_mut().zip(q.dual.to_array()) {
            *sum += x * signed;
        }
    }
    let real = DQuat::from_array(real);
    let inv_norm = 1.0 / real.length();
    DualQuat {
        real: real * inv_norm,
        dual: DQuat::from_array(dual) * inv_norm,
    }
}

impl DualQuaternionSkinning {
    pub fn new(weights: &SkinWeights) -> Self {
        Self {
            csr: PivotedWeights::new(weights),
        }
    }

    pub fn num_vertices(&self) -> usize {
        self.csr.num_vertices()
    }

    pub fn num_joints(&self) -> usize {
        self.csr.num_joints
    }

    /// Heaviest joint of vertex `v` (the antipodality pivot).
    pub fn pivot(&self, v: usize) -> usize {
        self.csr.pivot[v] as usize
    }

    /// Fills `scratch` with the joint dual quaternions of `transforms` (`#J`, serial).
    pub fn prepare(&self, transforms: &[DAffine3], scratch: &mut DqsScratch) {
        assert_eq!(transforms.len(), self.csr.num_joints, "DQS: transforms");
        assert_eq!(
            scratch.joint_dual_quats.len(),
            self.csr.num_joints,
            "DQS: scratch"
        );
        for (q, t) in scratch.joint_dual_quats.iter_mut().zip(transforms) {
            *q = DualQuat::from_affine(t);
        }
    }

    /// M' = DQS(T, Ω, M) (Eq. 4). `transforms`: `#J`; `scratch`: `DqsScratch::new(#J)`;
    /// `rest_positions`, `out`: `#V`.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(
        &self,
        transforms: &[DAffine3],
        rest_positions: &[DVec3],
        scratch: &mut DqsScratch,
        out: &mut [DVec3],
    ) {
        self.prepare(transforms, scratch);
        assert_eq!(rest_positions.len(), self.num_vertices(), "DQS: rest");
        assert_eq!(out.len(), self.num_vertices(), "DQS: out");
        let joint_dual_quats = &scratch.joint_dual_quats[..];
        out.par_chunks_mut(VERTEX_GRAIN)
            .zip(rest_positions.par_chunks(VERTEX_GRAIN))
            .enumerate()
            .for_each(|(chunk, (out_chunk, rest_chunk))| {
                let first = chunk * VERTEX_GRAIN;
                let row_start = &self.csr.row_start[first..=first + out_chunk.len()];
                let pivots = &self.csr.pivot[first..first + out_chunk.len()];
                for (((o, &p), bounds), &pivot) in out_chunk
                    .iter_mut()
                    .zip(rest_chunk)
                    .zip(row_start.windows(2))
                    .zip(pivots)
                {
                    let range = bounds[0] as usize..bounds[1] as usize;
                    *o = if range.is_empty() {
                        p
                    } else {
                        blend_dual_quats(
                            &self.csr.joints[range.clone()],
                            &self.csr.weights[range],
                            pivot as usize,
                            joint_dual_quats,
                        )
                        .transform_point3(p)
                    };
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::{FRAC_PI_2, PI};

    fn skin(weights: &[Vec<f64>], transforms: &[DAffine3], rest: &[DVec3]) -> Vec<DVec3> {
        let (w, _) = SkinWeights::from_dense(weights).unwrap();
        let dqs = DualQuaternionSkinning::new(&w);
        let mut scratch = DqsScratch::new(transforms.len());
        let mut out = vec![DVec3::ZERO; rest.len()];
        dqs.apply(transforms, rest, &mut scratch, &mut out);
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
            out[0].abs_diff_eq(DVec3::new(1.0, 3.0, 5.0), 1e-14),
            "{out:?}"
        );
    }

    #[test]
    fn half_half_twist_preserves_distance_to_axis() {
        // ±90° twists about x blend to the identity rotation: no candy-wrapper collapse.
        let t = [
            DAffine3::from_rotation_x(FRAC_PI_2),
            DAffine3::from_rotation_x(-FRAC_PI_2),
        ];
        let p = DVec3::new(3.0, 1.0, 2.0);
        let out = skin(&[vec![0.5, 0.5]], &t, &[p]);
        assert!(out[0].abs_diff_eq(p, 1e-14), "{out:?}");
        // 30/70 blend of 0 and 90°: rotation by 63° about x, length preserved.
        let t = [DAffine3::IDENTITY, DAffine3::from_rotation_x(FRAC_PI_2)];
        let out = skin(&[vec![0.3, 0.7]], &t, &[p]);
        assert!((out[0].length() - p.length()).abs() < 1e-14);
        assert!((out[0].x - p.x).abs() < 1e-14);
    }

    #[test]
    fn pivot_sign_rule_handles_opposite_quaternions() {
        // Rotations by +170° and −170° about z: as quaternions they are nearly antipodal. The
        // correct blend is the 180° rotation; without sign alignment it would be ≈ identity.
        let t = [
            DAffine3::from_rotation_z(170f64.to_radians()),
            DAffine3::from_rotation_z(-170f64.to_radians()),
        ];
        let out = skin(&[vec![0.5, 0.5]], &t, &[DVec3::X]);
        assert!(out[0].abs_diff_eq(-DVec3::X, 1e-14), "{out:?}");
        // Same rotation stored with opposite quaternion signs is blended as one rotation.
        let q = DQuat::from_rotation_y(PI / 3.0);
        let mut scratch = DqsScratch::new(2);
        scratch.joint_dual_quats = vec![
            DualQuat::from_rotation_translation(q, DVec3::X),
            DualQuat::from_rotation_translation(-q, DVec3::X),
        ];
        let b = blend_dual_quats(&[0, 1], &[0.4, 0.6], 1, &scratch.joint_dual_quats);
        let expected = DAffine3::from_translation(DVec3::X) * DAffine3::from_quat(q);
        let p = DVec3::new(0.3, -2.0, 1.0);
        assert!(
            b.transform_point3(p)
                .abs_diff_eq(expected.transform_point3(p), 1e-14)
        );
    }
}
