//! Dual quaternion skinning (Kavan et al. 2008; Eq. 4): `v'_i = DQBlend(T_i, Ω_i) v_i`.
//!
//! Per joint, `T_j` becomes a unit dual quaternion `q̂_j = r_j + ε d_j` with `d_j = ½ t_j r_j`.
//! Per vertex, terms are sign-aligned with the **heaviest** influence (antipodality pivot; the
//! reference tool uses the first listed joint, which can flip the blend when that joint has a tiny
//! weight), blended with Ω, normalised and applied as `v' = R v + t`, `t = 2 (d r*)_xyz`
//! (evaluated without normalising first, see [`dqs_point`]).
//!
//! The per-vertex rule is written once over [`SkinReal`]: [`DualQuaternionSkinning`] is its f64
//! instance (the exact path), [`super::DqsF32`] its f32 instance (the display path); both run on
//! the count-sorted layout of [`super::compact_weights`].
//!
//! DQS handles rigid transforms only: a `T_j^r` that is not a rotation is replaced by its
//! rotation polar factor ([`super::rigid_rotation`]); scale/shear are dropped, `T_j^t` kept.

use glam::{DAffine3, DQuat, DVec3};

use super::antipodal_signs::AntipodalSigns;
use super::compact_weights::{
    BLOCK, Block, CountSortedWeights, RestPoints, VertexKernel, WorldPoints,
};
use super::precision::SkinReal;
use super::rigid_rotation::rotation_quaternion;
use crate::SkinWeights;

/// A dual quaternion `real + ε dual`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DualQuat {
    /// Real part: the rotation (unit for a rigid transform).
    pub real: DQuat,
    /// Dual part: ½ (translation, 0) · real for a rigid transform.
    pub dual: DQuat,
}

impl DualQuat {
    /// The identity transform (`1 + ε 0`).
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

/// Caller-owned per-frame buffer of a DQS kernel of precision `S`: the `#J` joint dual
/// quaternions `[real, dual]` (of `T_j ∘ translate(o)` for the f32 kernel).
#[derive(Debug, Clone)]
pub struct DqsScratch<S: SkinReal = f64> {
    pub(crate) joint_dual_quats: Vec<[S::Quat; 2]>,
    pub(crate) signs: AntipodalSigns<S>,
}

impl<S: SkinReal> DqsScratch<S> {
    /// A buffer for `num_joints` (`#J`) joints, initialised to identities.
    pub fn new(num_joints: usize) -> Self {
        Self {
            joint_dual_quats: vec![[S::quat(DQuat::IDENTITY), S::ZERO_QUAT]; num_joints],
            signs: AntipodalSigns::new(num_joints),
        }
    }

    /// Fills the joint dual quaternions of `T_j ∘ translate(origin)` (`#J`, built in f64, then
    /// rounded to `S`; DQS blending commutes with that right factor) and, where a mesh of
    /// `sorted`'s size gains from it, the sign table. Returns whether the table was filled (the
    /// per-vertex rule then reads its signs, `TABLE = true`).
    pub(crate) fn prepare(
        &mut self,
        transforms: &[DAffine3],
        origin: DVec3,
        sorted: &CountSortedWeights<S>,
    ) -> bool {
        assert_eq!(
            self.joint_dual_quats.len(),
            transforms.len(),
            "DQS: scratch"
        );
        let to_local = DAffine3::from_translation(origin);
        for (q, t) in self.joint_dual_quats.iter_mut().zip(transforms) {
            let dq = DualQuat::from_affine(&(*t * to_local));
            *q = [S::quat(dq.real), S::quat(dq.dual)];
        }
        let dual_quats = &self.joint_dual_quats;
        self.signs
            .fill_if_worth_it(&sorted.sign_pairs, sorted.num_vertices(), |j| {
                dual_quats[j][0]
            })
    }

    /// [`Self::prepare`], then skins `out` with `sorted` and `points`.
    pub(crate) fn skin<P: RestPoints<S>>(
        &mut self,
        transforms: &[DAffine3],
        origin: DVec3,
        sorted: &CountSortedWeights<S>,
        points: P,
        out: &mut [S::Out],
    ) {
        let table = self.prepare(transforms, origin, sorted);
        let dual_quats = &self.joint_dual_quats;
        if table {
            let rule = DqsRule::<S, P, true> {
                joint_dual_quats: dual_quats,
                signs: &self.signs,
                points,
            };
            sorted.skin(&rule, out);
        } else {
            let rule = DqsRule::<S, P, false> {
                joint_dual_quats: dual_quats,
                signs: &self.signs,
                points,
            };
            sorted.skin(&rule, out);
        }
    }
}

/// Precomputed DQS (f64, the exact path): Ω count-sorted with each vertex's pivot joint.
#[derive(Debug, Clone)]
pub struct DualQuaternionSkinning {
    sorted: CountSortedWeights<f64>,
}

/// Sign-aligned blend `Σ_j ω_j s_j q̂_j`, `s_j = sign(r_pivot · r_j)`, applied to `p` without
/// normalising first: with `n = |Σ ω s r|²`, `R p = ((w² − v·v) p + 2 (v·p) v + 2 w v×p) / n`
/// and `t = 2 (w d_v − d_w v + v × d_v) / n` (one division, no square root; Eq. 4).
/// `TABLE`: the signs come from `signs` (the pivot's row of [`AntipodalSigns`]) instead of dot
/// products (same values).
#[inline(always)]
pub(crate) fn dqs_point<S: SkinReal, const TABLE: bool>(
    joints: &[u16],
    weights: &[S],
    pivot: usize,
    signs: &[S],
    joint_dual_quats: &[[S::Quat; 2]],
    p: S::V3,
) -> S::V3 {
    let pivot_real = joint_dual_quats[pivot][0];
    let mut real = S::ZERO_QUAT;
    let mut dual = S::ZERO_QUAT;
    for (&j, &w) in joints.iter().zip(weights) {
        let [r, d] = joint_dual_quats[usize::from(j)];
        let signed = if TABLE {
            w * signs[usize::from(j)]
        } else {
            w.copysign(S::quat_dot(pivot_real, r))
        };
        real = real + r * signed;
        dual = dual + d * signed;
    }
    let (v, w) = S::quat_parts(real);
    let (dv, dw) = S::quat_parts(dual);
    let rotated = rotate_unnormalised::<S>(v, w, p);
    let translation = (dv * w - v * dw + S::cross(v, dv)) * S::TWO;
    (rotated + translation) * (S::length_squared(v) + w * w).recip()
}

/// [`dqs_point`] of a count-sorted vertex whose heaviest influence is `pivot`: with `TABLE` the
/// signs are that joint's row of `signs`, otherwise computed (the rule of [`DqsRule`] and of the
/// DQS part of blended skinning).
#[inline(always)]
pub(crate) fn dqs_point_at_pivot<S: SkinReal, const TABLE: bool>(
    joints: &[u16],
    weights: &[S],
    pivot: u16,
    signs: &AntipodalSigns<S>,
    joint_dual_quats: &[[S::Quat; 2]],
    p: S::V3,
) -> S::V3 {
    let pivot = usize::from(pivot);
    let row = if TABLE { signs.row(pivot) } else { &[] };
    dqs_point::<S, TABLE>(joints, weights, pivot, row, joint_dual_quats, p)
}

/// `|q|² R(q) p` for a quaternion `q = (v, w)` of any non-zero length (R(q) the rotation of
/// `q / |q|`): `(w² − v·v) p + 2 (v·p) v + 2 w v × p`.
#[inline(always)]
pub(crate) fn rotate_unnormalised<S: SkinReal>(v: S::V3, w: S, p: S::V3) -> S::V3 {
    p * (w * w - S::length_squared(v)) + v * (S::TWO * S::dot(v, p)) + S::cross(v, p) * (S::TWO * w)
}

/// The per-vertex DQS rule for a kernel of precision `S` (`TABLE`: signs looked up).
struct DqsRule<'a, S: SkinReal, P, const TABLE: bool> {
    joint_dual_quats: &'a [[S::Quat; 2]],
    signs: &'a AntipodalSigns<S>,
    points: P,
}

impl<S: SkinReal, P: RestPoints<S>, const TABLE: bool> VertexKernel<S>
    for DqsRule<'_, S, P, TABLE>
{
    #[inline(always)]
    fn skin(&self, joints: &[u16], weights: &[S], pivot: u16, slot: usize, vertex: usize) -> S::V3 {
        dqs_point_at_pivot::<S, TABLE>(
            joints,
            weights,
            pivot,
            self.signs,
            self.joint_dual_quats,
            self.points.point(slot, vertex),
        )
    }

    /// With the sign table: the `BLOCK` blends are accumulated per vertex, then the
    /// normalisation and the rigid map are evaluated across the block (one SIMD lane per
    /// vertex), in the order of operations of [`dqs_point`] (bit-identical results).
    #[inline(always)]
    fn skin_block<const K: usize>(&self, block: &Block<'_, S>) -> [S::V3; BLOCK] {
        if !TABLE {
            return block.one_by_one::<K>(self);
        }
        let mut blend = [[S::ZERO; 8]; BLOCK];
        block.for_each_influence::<K>(|l, pivot, j, w| {
            let signed = w * self.signs.row(pivot)[j];
            let [r, d] = self.joint_dual_quats[j];
            let (q, e) = (S::quat_array(r), S::quat_array(d));
            let sum = &mut blend[l];
            for c in 0..4 {
                sum[c] = sum[c] + q[c] * signed;
                sum[4 + c] = sum[4 + c] + e[c] * signed;
            }
        });
        // Component-major copies (lane l = vertex l), so the tail is vectorised across lanes.
        let [x, y, z, w, dx, dy, dz, dw]: [[S; BLOCK]; 8] =
            std::array::from_fn(|c| std::array::from_fn(|l| blend[l][c]));
        let points: [[S; 3]; BLOCK] = std::array::from_fn(|l| {
            S::components(self.points.point(block.slot + l, block.vertices[l]))
        });
        let [px, py, pz]: [[S; BLOCK]; 3] =
            std::array::from_fn(|c| std::array::from_fn(|l| points[l][c]));
        let mut out = [[S::ZERO; BLOCK]; 3];
        for l in 0..BLOCK {
            let (x, y, z, w) = (x[l], y[l], z[l], w[l]);
            let (dx, dy, dz, dw) = (dx[l], dy[l], dz[l], dw[l]);
            let (px, py, pz) = (px[l], py[l], pz[l]);
            let vv = x * x + y * y + z * z;
            let a = w * w - vv;
            let b = S::TWO * (x * px + y * py + z * pz);
            let c = S::TWO * w;
            let (cx, cy, cz) = (y * pz - z * py, z * px - x * pz, x * py - y * px);
            let (ex, ey, ez) = (y * dz - z * dy, z * dx - x * dz, x * dy - y * dx);
            let inv = (vv + w * w).recip();
            out[0][l] = (px * a + x * b + cx * c + (dx * w - x * dw + ex) * S::TWO) * inv;
            out[1][l] = (py * a + y * b + cy * c + (dy * w - y * dw + ey) * S::TWO) * inv;
            out[2][l] = (pz * a + z * b + cz * c + (dz * w - z * dw + ez) * S::TWO) * inv;
        }
        std::array::from_fn(|l| S::new_v3(out[0][l], out[1][l], out[2][l]))
    }

    #[inline(always)]
    fn unweighted(&self, slot: usize, vertex: usize) -> S::V3 {
        self.points.world(slot, vertex)
    }
}

impl DualQuaternionSkinning {
    /// Precomputes the kernel from Ω (`#V × #J`).
    pub fn new(weights: &SkinWeights) -> Self {
        Self {
            sorted: CountSortedWeights::new(weights),
        }
    }

    /// Number of mesh vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.sorted.num_vertices()
    }

    /// Number of joints `#J`.
    pub fn num_joints(&self) -> usize {
        self.sorted.num_joints
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
        assert_eq!(transforms.len(), self.num_joints(), "DQS: transforms");
        assert_eq!(rest_positions.len(), self.num_vertices(), "DQS: rest");
        scratch.skin(
            transforms,
            DVec3::ZERO,
            &self.sorted,
            WorldPoints(rest_positions),
            out,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skinning::dqs_f32::{DqsF32, DqsF32Scratch};
    use glam::Vec3;
    use std::f64::consts::{FRAC_PI_2, PI};

    /// M' of both instances of the rule: the f64 kernel and the f32 display kernel.
    fn skin(
        weights: &[Vec<f64>],
        transforms: &[DAffine3],
        rest: &[DVec3],
    ) -> (Vec<DVec3>, Vec<Vec3>) {
        let (w, _) = SkinWeights::from_dense(weights).unwrap();
        let dqs = DualQuaternionSkinning::new(&w);
        let mut scratch = DqsScratch::new(transforms.len());
        let mut out = vec![DVec3::ZERO; rest.len()];
        dqs.apply(transforms, rest, &mut scratch, &mut out);
        let dqs_f32 = DqsF32::new(&w, rest).unwrap();
        let mut out_f32 = vec![Vec3::ZERO; rest.len()];
        dqs_f32.apply(
            transforms,
            &mut DqsF32Scratch::new(transforms.len()),
            &mut out_f32,
        );
        (out, out_f32)
    }

    #[test]
    fn single_bone_rotation_about_a_point() {
        let pivot = DVec3::new(1.0, 2.0, 0.0);
        let t = DAffine3::from_translation(pivot)
            * DAffine3::from_rotation_z(FRAC_PI_2)
            * DAffine3::from_translation(-pivot);
        let (out, out_f32) = skin(&[vec![1.0]], &[t], &[DVec3::new(2.0, 2.0, 5.0)]);
        let expected = DVec3::new(1.0, 3.0, 5.0);
        assert!(out[0].abs_diff_eq(expected, 1e-14), "{out:?}");
        assert!(
            out_f32[0].abs_diff_eq(expected.as_vec3(), 1e-6),
            "{out_f32:?}"
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
        let (out, out_f32) = skin(&[vec![0.5, 0.5]], &t, &[p]);
        assert!(out[0].abs_diff_eq(p, 1e-14), "{out:?}");
        assert!(out_f32[0].abs_diff_eq(p.as_vec3(), 1e-6), "{out_f32:?}");
        // 30/70 blend of 0 and 90°: rotation by 63° about x, length preserved.
        let t = [DAffine3::IDENTITY, DAffine3::from_rotation_x(FRAC_PI_2)];
        let (out, _) = skin(&[vec![0.3, 0.7]], &t, &[p]);
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
        let (out, out_f32) = skin(&[vec![0.5, 0.5]], &t, &[DVec3::X]);
        assert!(out[0].abs_diff_eq(-DVec3::X, 1e-14), "{out:?}");
        assert!(out_f32[0].abs_diff_eq(-Vec3::X, 1e-6), "{out_f32:?}");
        // Same rotation stored with opposite quaternion signs is blended as one rotation.
        let q = DQuat::from_rotation_y(PI / 3.0);
        let dual_quats = [q, -q].map(|q| {
            let dq = DualQuat::from_rotation_translation(q, DVec3::X);
            [dq.real, dq.dual]
        });
        let p = DVec3::new(0.3, -2.0, 1.0);
        let blended = dqs_point::<f64, false>(&[0, 1], &[0.4, 0.6], 1, &[], &dual_quats, p);
        let with_table =
            dqs_point::<f64, true>(&[0, 1], &[0.4, 0.6], 1, &[-1.0, 1.0], &dual_quats, p);
        assert_eq!(blended, with_table);
        let expected = DAffine3::from_translation(DVec3::X) * DAffine3::from_quat(q);
        assert!(blended.abs_diff_eq(expected.transform_point3(p), 1e-14));
    }

    #[test]
    fn sign_table_and_count_sorting_match_the_plain_per_vertex_rule_bitwise() {
        // 3 joints, 20 000 vertices (3 chunks, table used since 9 ≤ #V), 1–3 influences per
        // vertex, joint 2 rotated by ±170° so that signs flip.
        let (rows, rest) = crate::skinning::test_fixtures::twenty_thousand_vertices();
        let t = [
            DAffine3::from_translation(DVec3::Y) * DAffine3::from_rotation_x(0.4),
            DAffine3::from_rotation_z(170f64.to_radians()),
            DAffine3::from_rotation_z(-170f64.to_radians()),
        ];
        let (w, _) = SkinWeights::from_dense(&rows).unwrap();
        let (out, _) = skin(&rows, &t, &rest);
        let dual_quats: Vec<[DQuat; 2]> = t
            .iter()
            .map(|t| {
                let dq = DualQuat::from_affine(t);
                [dq.real, dq.dual]
            })
            .collect();
        for (v, (&o, &p)) in out.iter().zip(&rest).enumerate() {
            let (joints, weights) = w.row(v);
            let joints: Vec<u16> = joints.iter().map(|&j| j as u16).collect();
            let pivot = w.heaviest(v).unwrap();
            let expected = dqs_point::<f64, false>(&joints, weights, pivot, &[], &dual_quats, p);
            assert_eq!(o, expected, "vertex {v}");
        }
    }
}
