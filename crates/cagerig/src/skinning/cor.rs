//! Optimized centres-of-rotation skinning (Le & Hodgins 2016; Eq. 6):
//!
//! `R(i)` = normalised quaternion blend of the joint rotations (sign-aligned with the heaviest
//! influence, as in DQS), `p̃_i = Σ_j ω_ij (T_j^r p_i + T_j^t)` (the LBS image of the CoR p_i),
//! `t(i) = p̃_i − R(i) p_i`, and `v'_i = R(i) v_i + t(i) = R(i) (v_i − p_i) + p̃_i`.
//!
//! The centres p_i (`#V`) are passed to [`CorSkinning::apply`]: they follow the rest cage
//! (CoRs = Λ·C, Eq. 14) and are computed by [`super::cor_centres`].
//!
//! **No CoR ⇒ LBS.** With `p_i = v_i` the formula reduces exactly to LBS for that vertex. This is
//! how [`super::cor_centres::compute_cor_centres`] encodes vertices without a centre (single
//! influence, zero total similarity), and a non-finite `p_i` is treated the same way here.
//! For a single-influence vertex the result is the rigid `T_j v_i` whatever p_i is.
//!
//! Rotations of non-rigid `T_j^r` are their polar factors ([`super::rigid_rotation`]); `p̃_i`
//! uses the full affine `T_j`.

use glam::{DAffine3, DMat3, DQuat, DVec3};
use rayon::prelude::*;

use super::VERTEX_GRAIN;
use super::lbs::{blend_affine_cols, transform_point_cols};
use super::pivoted_weights::PivotedWeights;
use super::rigid_rotation::rotation_quaternion;
use crate::SkinWeights;

/// Caller-owned per-frame buffer: the `#J` joint rotation quaternions.
#[derive(Debug, Clone)]
pub struct CorScratch {
    joint_rotations: Vec<DQuat>,
}

impl CorScratch {
    pub fn new(num_joints: usize) -> Self {
        Self {
            joint_rotations: vec![DQuat::IDENTITY; num_joints],
        }
    }

    /// The joint rotations of the last `apply`.
    pub fn joint_rotations(&self) -> &[DQuat] {
        &self.joint_rotations
    }
}

/// Precomputed CoR skinning: flat Ω (CSR) and the per-vertex pivot (heaviest) joint.
#[derive(Debug, Clone)]
pub struct CorSkinning {
    csr: PivotedWeights,
}

/// Normalised sign-aligned quaternion blend `Σ_j ω_j s_j r_j / |…|` (DQBlendRot).
#[inline(always)]
pub(crate) fn blend_rotations(
    joints: &[u32],
    weights: &[f64],
    pivot: usize,
    joint_rotations: &[DQuat],
) -> DQuat {
    let pivot_rotation = joint_rotations[pivot];
    let mut sum = [0.0f64; 4];
    for (&j, &w) in joints.iter().zip(weights) {
        let q = joint_rotations[j as usize];
        let signed = w.copysign(pivot_rotation.dot(q));
        for (s, x) in sum.iter_mut().zip(q.to_array()) {
            *s += x * signed;
        }
    }
    let sum = DQuat::from_array(sum);
    sum * (1.0 / sum.length())
}

impl CorSkinning {
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

    /// Fills `scratch` with the joint rotation quaternions of `transforms` (`#J`, serial).
    pub fn prepare(&self, transforms: &[DAffine3], scratch: &mut CorScratch) {
        assert_eq!(transforms.len(), self.csr.num_joints, "CoR: transforms");
        assert_eq!(
            scratch.joint_rotations.len(),
            self.csr.num_joints,
            "CoR: scratch"
        );
        for (q, t) in scratch.joint_rotations.iter_mut().zip(transforms) {
            *q = rotation_quaternion(t.matrix3);
        }
    }

    /// The blended rotation `R(i)` of vertex `v` (needs a prepared `scratch`); identity for an
    /// unweighted vertex.
    pub fn blended_rotation(&self, v: usize, scratch: &CorScratch) -> DMat3 {
        let range = self.csr.row_start[v] as usize..self.csr.row_start[v + 1] as usize;
        if range.is_empty() {
            return DMat3::IDENTITY;
        }
        DMat3::from_quat(blend_rotations(
            &self.csr.joints[range.clone()],
            &self.csr.weights[range],
            self.csr.pivot[v] as usize,
            &scratch.joint_rotations,
        ))
    }

    /// M' = CoR(T, Ω, M, P) (Eq. 6). `transforms`: `#J`; `scratch`: `CorScratch::new(#J)`;
    /// `rest_positions`, `centres` (p_i, rest space), `out`: `#V`.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(
        &self,
        transforms: &[DAffine3],
        rest_positions: &[DVec3],
        centres: &[DVec3],
        scratch: &mut CorScratch,
        out: &mut [DVec3],
    ) {
        self.prepare(transforms, scratch);
        assert_eq!(rest_positions.len(), self.num_vertices(), "CoR: rest");
        assert_eq!(centres.len(), self.num_vertices(), "CoR: centres");
        assert_eq!(out.len(), self.num_vertices(), "CoR: out");
        let joint_rotations = &scratch.joint_rotations[..];
        out.par_chunks_mut(VERTEX_GRAIN)
            .zip(rest_positions.par_chunks(VERTEX_GRAIN))
            .zip(centres.par_chunks(VERTEX_GRAIN))
            .enumerate()
            .for_each(|(chunk, ((out_chunk, rest_chunk), centre_chunk))| {
                let first = chunk * VERTEX_GRAIN;
                let row_start = &self.csr.row_start[first..=first + out_chunk.len()];
                let pivots = &self.csr.pivot[first..first + out_chunk.len()];
                for ((((o, &p), &c), bounds), &pivot) in out_chunk
                    .iter_mut()
                    .zip(rest_chunk)
                    .zip(centre_chunk)
                    .zip(row_start.windows(2))
                    .zip(pivots)
                {
                    let range = bounds[0] as usize..bounds[1] as usize;
                    if range.is_empty() {
                        *o = p;
                        continue;
                    }
                    let joints = &self.csr.joints[range.clone()];
                    let weights = &self.csr.weights[range];
                    let blended = blend_affine_cols(joints, weights, transforms);
                    if !c.is_finite() {
                        *o = transform_point_cols(&blended, p);
                        continue;
                    }
                    let rotation =
                        blend_rotations(joints, weights, pivot as usize, joint_rotations);
                    *o = rotation.mul_vec3(p - c) + transform_point_cols(&blended, c);
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn skin(
        weights: &[Vec<f64>],
        transforms: &[DAffine3],
        rest: &[DVec3],
        centres: &[DVec3],
    ) -> Vec<DVec3> {
        let (w, _) = SkinWeights::from_dense(weights).unwrap();
        let cor = CorSkinning::new(&w);
        let mut scratch = CorScratch::new(transforms.len());
        let mut out = vec![DVec3::ZERO; rest.len()];
        cor.apply(transforms, rest, centres, &mut scratch, &mut out);
        out
    }

    #[test]
    fn elbow_bend_with_centre_on_the_joint_is_rigid_about_it() {
        // Bone 0 fixed, bone 1 rotates 90° about z around the elbow e. A vertex with 50/50
        // weights and its CoR at e is rotated by 45° about e (LBS would pull it inwards).
        let e = DVec3::new(1.0, 0.0, 0.0);
        let bend = DAffine3::from_translation(e)
            * DAffine3::from_rotation_z(FRAC_PI_2)
            * DAffine3::from_translation(-e);
        let v = DVec3::new(1.0, 0.5, 0.0);
        let out = skin(&[vec![0.5, 0.5]], &[DAffine3::IDENTITY, bend], &[v], &[e]);
        let expected = e + DQuat::from_rotation_z(FRAC_PI_2 / 2.0).mul_vec3(v - e);
        assert!(out[0].abs_diff_eq(expected, 1e-14), "{out:?} vs {expected}");
        assert!((out[0].distance(e) - 0.5).abs() < 1e-14);
    }

    #[test]
    fn centre_at_vertex_or_non_finite_gives_lbs() {
        let t = [
            DAffine3::from_rotation_x(0.4),
            DAffine3::from_translation(DVec3::Y) * DAffine3::from_rotation_y(-1.1),
        ];
        let v = DVec3::new(0.3, 0.7, -1.2);
        let lbs = (t[0].matrix3 * 0.25 + t[1].matrix3 * 0.75) * v
            + (t[0].translation * 0.25 + t[1].translation * 0.75);
        for c in [v, DVec3::NAN] {
            let out = skin(&[vec![0.25, 0.75]], &t, &[v], &[c]);
            assert!(out[0].abs_diff_eq(lbs, 1e-14), "{out:?} vs {lbs}");
        }
    }
}
