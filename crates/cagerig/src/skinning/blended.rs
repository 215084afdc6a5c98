//! Blended LBS/DQS skinning, Maya's "weight blended" skin cluster (ufbx's
//! `UFBX_SKINNING_METHOD_BLENDED_DQ_LINEAR`): vertex v with DQ blend weight `b_v` ∈ [0, 1]
//! ([`super::DqBlendWeights`]) is skinned by the blend of the two skinning matrices,
//! `M_v = (1 − b_v) Σ_j ω_vj T_j + b_v DQ_v`, with `DQ_v` the rigid map of the normalised
//! dual-quaternion blend (Eq. 4). Applied to the rest point this is
//! `v' = (1 − b_v)·LBS(v) + b_v·DQS(v)` (Eq. 2–3 and 4): the matrix blend is linear in the point.
//!
//! The rule is written once over [`SkinReal`] on the count-sorted layout of
//! [`super::compact_weights`]: [`BlendedSkinning`] is its f64 instance (the exact path),
//! [`super::BlendedF32`] its f32 instance (the display path). A vertex with `b_v = 0` runs the
//! LBS rule alone and one with `b_v = 1` the DQS rule alone, so those vertices have the bits of
//! [`super::LinearBlendSkinning`] / [`super::DualQuaternionSkinning`].
//!
//! Differences from ufbx's evaluation (`ufbx_get_skin_vertex_matrix`), none of which matters
//! for rigid joint transforms with normalised weights: the DQ part is sign-aligned with the
//! heaviest influence (ufbx: the first listed one; they differ only when two influences are
//! more than 90° apart as quaternions); the DQ part keeps the rotation polar factor of `T_j`
//! and drops joint scale (ufbx blends the scales of the joints' bind transforms); weights are
//! used as stored (Ω is normalised when a rig is built).

use glam::{DAffine3, DVec3};

use super::antipodal_signs::AntipodalSigns;
use super::compact_weights::{
    CountSortedWeights, JointColumns, RestPoints, VertexKernel, WorldPoints,
};
use super::dq_blend_weights::DqBlendWeights;
use super::dqs::{DqsScratch, dqs_point_at_pivot};
use super::lbs::{blend_columns, transform_point};
use super::precision::SkinReal;
use crate::{RigError, SkinWeights};

/// The per-vertex blended rule: LBS columns `transforms`, DQS joint dual quaternions (`TABLE`:
/// signs looked up), per-vertex blend weights `blend` (`#V`, by vertex).
pub(crate) struct BlendedRule<'a, S: SkinReal, T: ?Sized, P, const TABLE: bool> {
    pub transforms: &'a T,
    pub joint_dual_quats: &'a [[S::Quat; 2]],
    pub signs: &'a AntipodalSigns<S>,
    pub blend: &'a [S],
    pub points: P,
}

impl<'a, S: SkinReal, T: JointColumns<S> + ?Sized, P: RestPoints<S>, const TABLE: bool>
    BlendedRule<'a, S, T, P, TABLE>
{
    /// The rule of the LBS columns `transforms` and the DQS part of `dqs` (filled for this
    /// frame), with the blend weights `blend` (`#V`, by vertex) and the rest `points`.
    fn new(dqs: &'a DqsScratch<S>, transforms: &'a T, blend: &'a [S], points: P) -> Self {
        Self {
            transforms,
            joint_dual_quats: &dqs.joint_dual_quats,
            signs: &dqs.signs,
            blend,
            points,
        }
    }

    /// The LBS part at the rest point `p`.
    #[inline(always)]
    fn lbs_point(&self, joints: &[u16], weights: &[S], p: S::V3) -> S::V3 {
        transform_point::<S>(&blend_columns(joints, weights, self.transforms), p)
    }

    /// The DQS part at the rest point `p` (signs aligned with the influence `pivot`).
    #[inline(always)]
    fn dqs_point(&self, joints: &[u16], weights: &[S], pivot: u16, p: S::V3) -> S::V3 {
        dqs_point_at_pivot::<S, TABLE>(joints, weights, pivot, self.signs, self.joint_dual_quats, p)
    }
}

impl<S: SkinReal, T: JointColumns<S> + ?Sized, P: RestPoints<S>, const TABLE: bool> VertexKernel<S>
    for BlendedRule<'_, S, T, P, TABLE>
{
    #[inline(always)]
    fn skin(&self, joints: &[u16], weights: &[S], pivot: u16, slot: usize, vertex: usize) -> S::V3 {
        let b = self.blend[vertex];
        let p = self.points.point(slot, vertex);
        // Methods, not closures: a closure the inliner leaves out of line loses the skinning
        // tier's instruction set (`simd_dispatch.rs`); these two were out of line in a build
        // of the CLI.
        if b == S::ZERO {
            self.lbs_point(joints, weights, p)
        } else if b == S::ONE {
            self.dqs_point(joints, weights, pivot, p)
        } else {
            self.lbs_point(joints, weights, p) * (S::ONE - b)
                + self.dqs_point(joints, weights, pivot, p) * b
        }
    }

    #[inline(always)]
    fn unweighted(&self, slot: usize, vertex: usize) -> S::V3 {
        self.points.world(slot, vertex)
    }
}

/// Fills the DQS part of `dqs` for `T_j ∘ translate(origin)` (`transforms`, `#J`) and skins
/// `out` (`#V`) with the LBS columns `columns` (of the same maps, already relative to
/// `origin`), `sorted`, `blend` (`#V`, by vertex) and `points`.
#[expect(clippy::too_many_arguments)]
pub(crate) fn skin_blended<S: SkinReal, T: JointColumns<S> + ?Sized, P: RestPoints<S>>(
    dqs: &mut DqsScratch<S>,
    transforms: &[DAffine3],
    columns: &T,
    origin: DVec3,
    sorted: &CountSortedWeights<S>,
    blend: &[S],
    points: P,
    out: &mut [S::Out],
) {
    if dqs.prepare(transforms, origin, sorted) {
        let rule = BlendedRule::<S, T, P, true>::new(dqs, columns, blend, points);
        sorted.skin(&rule, out);
    } else {
        let rule = BlendedRule::<S, T, P, false>::new(dqs, columns, blend, points);
        sorted.skin(&rule, out);
    }
}

/// Precomputed blended skinning (f64, the exact path): Ω count-sorted with each vertex's pivot
/// joint, and the DQ blend weights `b` (`#V`).
#[derive(Debug, Clone)]
pub struct BlendedSkinning {
    sorted: CountSortedWeights<f64>,
    blend: DqBlendWeights,
}

impl BlendedSkinning {
    /// Precomputes the kernel from Ω (`#V × #J`) and `b` (`#V`). Errors if the sizes differ.
    pub fn new(weights: &SkinWeights, blend: &DqBlendWeights) -> Result<Self, RigError> {
        blend.check_vertices(weights.num_vertices())?;
        Ok(Self {
            sorted: CountSortedWeights::new(weights),
            blend: blend.clone(),
        })
    }

    /// Number of mesh vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.sorted.num_vertices()
    }

    /// Number of joints `#J`.
    pub fn num_joints(&self) -> usize {
        self.sorted.num_joints
    }

    /// The DQ blend weights `b` (`#V`).
    pub fn dq_blend_weights(&self) -> &DqBlendWeights {
        &self.blend
    }

    /// M' = (1 − b)·LBS + b·DQS per vertex (Eq. 2–4). `transforms`: `#J`; `scratch`:
    /// `DqsScratch::new(#J)` (the f64 LBS part reads `transforms` directly);
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
        assert_eq!(transforms.len(), self.num_joints(), "blended: transforms");
        assert_eq!(rest_positions.len(), self.num_vertices(), "blended: rest");
        skin_blended::<f64, _, _>(
            scratch,
            transforms,
            transforms,
            DVec3::ZERO,
            &self.sorted,
            self.blend.values(),
            WorldPoints(rest_positions),
            out,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skinning::{DualQuaternionSkinning, LinearBlendSkinning};
    use std::f64::consts::FRAC_PI_2;

    fn skin(
        weights: &[Vec<f64>],
        blend: &[f64],
        transforms: &[DAffine3],
        rest: &[DVec3],
    ) -> Vec<DVec3> {
        let (w, _) = SkinWeights::from_dense(weights).unwrap();
        let b = DqBlendWeights::new(blend.to_vec()).unwrap();
        let kernel = BlendedSkinning::new(&w, &b).unwrap();
        let mut out = vec![DVec3::ZERO; rest.len()];
        kernel.apply(
            transforms,
            rest,
            &mut DqsScratch::new(transforms.len()),
            &mut out,
        );
        out
    }

    #[test]
    fn half_half_twist_blends_the_collapsed_and_the_rigid_point() {
        // ±90° twists about x: LBS collapses the point onto the axis, DQS keeps it; b = ¼ lands
        // a quarter of the way from the LBS point to the DQS point.
        let t = [
            DAffine3::from_rotation_x(FRAC_PI_2),
            DAffine3::from_rotation_x(-FRAC_PI_2),
        ];
        let p = DVec3::new(3.0, 1.0, 2.0);
        let rows = vec![vec![0.5, 0.5]; 3];
        let out = skin(&rows, &[0.0, 0.25, 1.0], &t, &[p; 3]);
        let lbs = DVec3::new(3.0, 0.0, 0.0);
        assert!(out[0].abs_diff_eq(lbs, 1e-14), "{out:?}");
        assert!(out[2].abs_diff_eq(p, 1e-14), "{out:?}");
        assert!(out[1].abs_diff_eq(lbs * 0.75 + p * 0.25, 1e-14), "{out:?}");
    }

    #[test]
    fn zero_and_one_have_the_bits_of_lbs_and_dqs() {
        // 20 000 vertices (several chunks, sign table in use), up to 3 influences.
        let (rows, rest) = crate::skinning::test_fixtures::twenty_thousand_vertices();
        let n = rest.len();
        let t = [
            DAffine3::from_translation(DVec3::Y) * DAffine3::from_rotation_x(0.4),
            DAffine3::from_rotation_z(170f64.to_radians()),
            DAffine3::from_scale(DVec3::splat(1.2)) * DAffine3::from_rotation_y(-2.0),
        ];
        let (w, _) = SkinWeights::from_dense(&rows).unwrap();
        let mut lbs = vec![DVec3::ZERO; n];
        LinearBlendSkinning::new(&w).apply(&t, &rest, &mut lbs);
        let mut dqs = vec![DVec3::ZERO; n];
        DualQuaternionSkinning::new(&w).apply(&t, &rest, &mut DqsScratch::new(3), &mut dqs);
        let blend: Vec<f64> = (0..n).map(|v| [0.0, 1.0, 0.3][v % 3]).collect();
        let out = skin(&rows, &blend, &t, &rest);
        for v in 0..n {
            match v % 3 {
                0 => assert_eq!(out[v], lbs[v], "vertex {v}"),
                1 => assert_eq!(out[v], dqs[v], "vertex {v}"),
                _ => assert!(
                    out[v].abs_diff_eq(lbs[v] * 0.7 + dqs[v] * 0.3, 1e-12),
                    "vertex {v}"
                ),
            }
        }
    }

    #[test]
    fn blend_weights_must_match_the_vertices() {
        let (w, _) = SkinWeights::from_dense(&[vec![1.0], vec![1.0]]).unwrap();
        let b = DqBlendWeights::new(vec![0.5]).unwrap();
        assert!(matches!(
            BlendedSkinning::new(&w, &b),
            Err(RigError::SizeMismatch {
                expected: 2,
                actual: 1,
                ..
            })
        ));
    }
}
