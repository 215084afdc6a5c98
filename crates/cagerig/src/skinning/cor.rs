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
//!
//! The per-vertex rule is written once over [`SkinReal`]: [`CorSkinning`] is its f64 instance
//! (the exact path), [`super::CorF32`] its f32 instance (the display path).

use glam::{DAffine3, DQuat, DVec3, Vec3A};

use super::antipodal_signs::AntipodalSigns;
use super::compact_weights::{BLOCK, Block, CountSortedWeights, JointColumns, VertexKernel};
use super::dqs::rotate_unnormalised;
use super::lbs::{blend_columns, transform_point};
use super::precision::SkinReal;
use super::rigid_rotation::rotation_quaternion;
use crate::SkinWeights;

/// Caller-owned per-frame buffer of a CoR kernel of precision `S`: the `#J` transforms as
/// columns (`T_j ∘ translate(o)` for the f32 kernel) and their rotation quaternions.
#[derive(Debug, Clone)]
pub struct CorScratch<S: SkinReal = f64> {
    pub(crate) columns: Vec<[S::V3; 4]>,
    pub(crate) rotations: Vec<S::Quat>,
    pub(crate) signs: AntipodalSigns<S>,
}

impl<S: SkinReal> CorScratch<S> {
    /// A buffer for `num_joints` (`#J`) joints, filled by each frame's skinning.
    pub fn new(num_joints: usize) -> Self {
        Self {
            columns: vec![[S::ZERO_V3; 4]; num_joints],
            rotations: vec![S::quat(DQuat::IDENTITY); num_joints],
            signs: AntipodalSigns::new(num_joints),
        }
    }

    /// Fills the columns of `T_j ∘ translate(origin)`, the rotation quaternions of `T_j`
    /// (`#J`, f64, then rounded to `S`) and, where `sorted`'s mesh gains from it, the sign
    /// table; then skins `out` from `points`.
    pub(crate) fn skin<P: CentredPoints<S>>(
        &mut self,
        transforms: &[DAffine3],
        origin: DVec3,
        sorted: &CountSortedWeights<S>,
        points: P,
        out: &mut [S::Out],
    ) {
        assert_eq!(self.rotations.len(), transforms.len(), "CoR: scratch");
        super::compact_weights::columns_from_local::<S>(transforms, origin, &mut self.columns);
        for (q, t) in self.rotations.iter_mut().zip(transforms) {
            *q = S::quat(rotation_quaternion(t.matrix3));
        }
        let rotations = &self.rotations;
        if self
            .signs
            .fill_if_worth_it(&sorted.sign_pairs, sorted.num_vertices(), |j| rotations[j])
        {
            sorted.skin(
                &CorRule::<S, P, true> {
                    scratch: self,
                    points,
                },
                out,
            );
        } else {
            sorted.skin(
                &CorRule::<S, P, false> {
                    scratch: self,
                    points,
                },
                out,
            );
        }
    }
}

/// Precomputed CoR skinning (f64, the exact path): Ω count-sorted with each vertex's pivot.
#[derive(Debug, Clone)]
pub struct CorSkinning {
    sorted: CountSortedWeights<f64>,
}

/// CoR image of one vertex: `R(i) (v − p) + (Σ_j ω_j T_j) p` with `R(i)` the normalised
/// sign-aligned quaternion blend (evaluated unnormalised, one division); `centre` = p in the
/// kernel's space, `offset` = v − p.
#[inline(always)]
#[expect(clippy::too_many_arguments)]
pub(crate) fn cor_point<S: SkinReal, T: JointColumns<S> + ?Sized, const TABLE: bool>(
    joints: &[u16],
    weights: &[S],
    pivot: usize,
    signs: &[S],
    transforms: &T,
    rotations: &[S::Quat],
    centre: S::V3,
    offset: S::V3,
) -> S::V3 {
    let pivot_rotation = rotations[pivot];
    let mut rotation = S::ZERO_QUAT;
    for (&j, &w) in joints.iter().zip(weights) {
        let q = rotations[usize::from(j)];
        let signed = if TABLE {
            w * signs[usize::from(j)]
        } else {
            w.copysign(S::quat_dot(pivot_rotation, q))
        };
        rotation = rotation + q * signed;
    }
    let blended = blend_columns(joints, weights, transforms);
    let (v, w) = S::quat_parts(rotation);
    let rotated = rotate_unnormalised::<S>(v, w, offset) * (S::length_squared(v) + w * w).recip();
    rotated + transform_point::<S>(&blended, centre)
}

/// Per-vertex inputs of the CoR rule: the centre p (kernel space) and the offset v − p.
pub(crate) trait CentredPoints<S: SkinReal>: Sync {
    fn centre_and_offset(&self, slot: usize, vertex: usize) -> [S::V3; 2];
    /// The rest position v in world coordinates.
    fn world(&self, slot: usize, vertex: usize) -> S::V3;
}

/// The caller's rest positions and centres (`#V` each, world, f64), read by vertex; a
/// non-finite centre means "no CoR" (p = v: LBS).
pub(crate) struct WorldCentredPoints<'a> {
    pub rest: &'a [DVec3],
    pub centres: &'a [DVec3],
}

impl CentredPoints<f64> for WorldCentredPoints<'_> {
    #[inline(always)]
    fn centre_and_offset(&self, _slot: usize, vertex: usize) -> [DVec3; 2] {
        let (v, c) = (self.rest[vertex], self.centres[vertex]);
        if c.is_finite() {
            [c, v - c]
        } else {
            [v, DVec3::ZERO]
        }
    }
    #[inline(always)]
    fn world(&self, _slot: usize, vertex: usize) -> DVec3 {
        self.rest[vertex]
    }
}

/// Stored f32 `[p − o, v − p]` per sorted slot and the origin `o`.
pub(crate) struct LocalCentredPoints<'a> {
    pub stored: &'a [[Vec3A; 2]],
    pub origin: Vec3A,
}

impl CentredPoints<f32> for LocalCentredPoints<'_> {
    #[inline(always)]
    fn centre_and_offset(&self, slot: usize, _vertex: usize) -> [Vec3A; 2] {
        self.stored[slot]
    }
    #[inline(always)]
    fn world(&self, slot: usize, _vertex: usize) -> Vec3A {
        let [c, d] = self.stored[slot];
        c + d + self.origin
    }
}

/// The per-vertex CoR rule for a kernel of precision `S` (`TABLE`: signs looked up).
struct CorRule<'a, S: SkinReal, P, const TABLE: bool> {
    scratch: &'a CorScratch<S>,
    points: P,
}

impl<S: SkinReal, P: CentredPoints<S>, const TABLE: bool> VertexKernel<S>
    for CorRule<'_, S, P, TABLE>
{
    #[inline(always)]
    fn skin(&self, joints: &[u16], weights: &[S], pivot: u16, slot: usize, vertex: usize) -> S::V3 {
        let [centre, offset] = self.points.centre_and_offset(slot, vertex);
        let pivot = usize::from(pivot);
        cor_point::<S, _, TABLE>(
            joints,
            weights,
            pivot,
            if TABLE {
                self.scratch.signs.row(pivot)
            } else {
                &[]
            },
            &self.scratch.columns[..],
            &self.scratch.rotations,
            centre,
            offset,
        )
    }

    /// With the sign table: the `BLOCK` blends (affine columns and rotation) are accumulated
    /// per vertex, then the rotation of the offset and the map of the centre are evaluated
    /// across the block, in the order of operations of [`cor_point`] (bit-identical results).
    #[inline(always)]
    fn skin_block<const K: usize>(&self, block: &Block<'_, S>) -> [S::V3; BLOCK] {
        if !TABLE {
            return block.one_by_one::<K>(self);
        }
        // Per vertex: [x_axis, y_axis, z_axis, translation] (12) then the rotation (4).
        let mut blend = [[S::ZERO; 16]; BLOCK];
        for (l, sum) in blend.iter_mut().enumerate() {
            let signs = self.scratch.signs.row(usize::from(block.pivots[l]));
            for k in 0..K {
                let j = usize::from(block.joints[l * K + k]);
                let w = block.weights[l * K + k];
                let columns = self.scratch.columns[j];
                for (c, column) in columns.iter().enumerate() {
                    let [a, b, d] = S::components(*column);
                    sum[3 * c] = sum[3 * c] + a * w;
                    sum[3 * c + 1] = sum[3 * c + 1] + b * w;
                    sum[3 * c + 2] = sum[3 * c + 2] + d * w;
                }
                let q = S::quat_array(self.scratch.rotations[j]);
                let signed = w * signs[j];
                for c in 0..4 {
                    sum[12 + c] = sum[12 + c] + q[c] * signed;
                }
            }
        }
        let inputs: [[S; 6]; BLOCK] = std::array::from_fn(|l| {
            let [c, d] = self
                .points
                .centre_and_offset(block.slot + l, block.vertices[l]);
            let [cx, cy, cz] = S::components(c);
            let [dx, dy, dz] = S::components(d);
            [cx, cy, cz, dx, dy, dz]
        });
        // Component-major copies (lane l = vertex l), so the tail is vectorised across lanes.
        let m: [[S; BLOCK]; 16] = std::array::from_fn(|c| std::array::from_fn(|l| blend[l][c]));
        let [cx, cy, cz, px, py, pz]: [[S; BLOCK]; 6] =
            std::array::from_fn(|c| std::array::from_fn(|l| inputs[l][c]));
        let mut out = [[S::ZERO; BLOCK]; 3];
        for l in 0..BLOCK {
            let (x, y, z, w) = (m[12][l], m[13][l], m[14][l], m[15][l]);
            let (cx, cy, cz, px, py, pz) = (cx[l], cy[l], cz[l], px[l], py[l], pz[l]);
            let vv = x * x + y * y + z * z;
            let a = w * w - vv;
            let b = S::TWO * (x * px + y * py + z * pz);
            let c = S::TWO * w;
            let inv = (vv + w * w).recip();
            let rotated = [
                (px * a + x * b + (y * pz - z * py) * c) * inv,
                (py * a + y * b + (z * px - x * pz) * c) * inv,
                (pz * a + z * b + (x * py - y * px) * c) * inv,
            ];
            for r in 0..3 {
                out[r][l] =
                    rotated[r] + (m[r][l] * cx + m[3 + r][l] * cy + m[6 + r][l] * cz + m[9 + r][l]);
            }
        }
        std::array::from_fn(|l| S::new_v3(out[0][l], out[1][l], out[2][l]))
    }

    #[inline(always)]
    fn unweighted(&self, slot: usize, vertex: usize) -> S::V3 {
        self.points.world(slot, vertex)
    }
}

impl CorSkinning {
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
        assert_eq!(transforms.len(), self.num_joints(), "CoR: transforms");
        assert_eq!(rest_positions.len(), self.num_vertices(), "CoR: rest");
        assert_eq!(centres.len(), self.num_vertices(), "CoR: centres");
        scratch.skin(
            transforms,
            DVec3::ZERO,
            &self.sorted,
            WorldCentredPoints {
                rest: rest_positions,
                centres,
            },
            out,
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skinning::cor_f32::{CorF32, CorF32Scratch};
    use glam::Vec3;
    use std::f64::consts::FRAC_PI_2;

    /// M' of both instances of the rule: the f64 kernel and the f32 display kernel.
    fn skin(
        weights: &[Vec<f64>],
        transforms: &[DAffine3],
        rest: &[DVec3],
        centres: &[DVec3],
    ) -> (Vec<DVec3>, Vec<Vec3>) {
        let (w, _) = SkinWeights::from_dense(weights).unwrap();
        let cor = CorSkinning::new(&w);
        let mut scratch = CorScratch::new(transforms.len());
        let mut out = vec![DVec3::ZERO; rest.len()];
        cor.apply(transforms, rest, centres, &mut scratch, &mut out);
        let cor_f32 = CorF32::new(&w, rest, centres).unwrap();
        let mut out_f32 = vec![Vec3::ZERO; rest.len()];
        cor_f32.apply(
            transforms,
            &mut CorF32Scratch::new(transforms.len()),
            &mut out_f32,
        );
        (out, out_f32)
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
        let (out, out_f32) = skin(&[vec![0.5, 0.5]], &[DAffine3::IDENTITY, bend], &[v], &[e]);
        let expected = e + DQuat::from_rotation_z(FRAC_PI_2 / 2.0).mul_vec3(v - e);
        assert!(out[0].abs_diff_eq(expected, 1e-14), "{out:?} vs {expected}");
        assert!((out[0].distance(e) - 0.5).abs() < 1e-14);
        assert!(
            out_f32[0].abs_diff_eq(expected.as_vec3(), 1e-6),
            "{out_f32:?}"
        );
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
            let (out, out_f32) = skin(&[vec![0.25, 0.75]], &t, &[v], &[c]);
            assert!(out[0].abs_diff_eq(lbs, 1e-14), "{out:?} vs {lbs}");
            assert!(
                out_f32[0].abs_diff_eq(lbs.as_vec3(), 1e-6),
                "{out_f32:?} vs {lbs}"
            );
        }
    }

    #[test]
    fn sign_table_and_blocks_match_the_plain_per_vertex_rule_bitwise() {
        // 3 joints, 20 000 vertices (3 chunks, table and blocks used), 1–3 influences, centres
        // finite or not, joint 2 rotated by ±170° so that signs flip.
        let (rows, rest) = crate::skinning::test_fixtures::twenty_thousand_vertices();
        let centres: Vec<DVec3> = rest
            .iter()
            .enumerate()
            .map(|(v, &p)| {
                if v % 5 == 0 {
                    DVec3::NAN
                } else {
                    p * 0.5 + DVec3::X
                }
            })
            .collect();
        let t = [
            DAffine3::from_translation(DVec3::Y) * DAffine3::from_rotation_x(0.4),
            DAffine3::from_rotation_z(170f64.to_radians()),
            DAffine3::from_scale(DVec3::new(1.0, 1.2, 0.9))
                * DAffine3::from_rotation_z(-170f64.to_radians()),
        ];
        let (w, _) = SkinWeights::from_dense(&rows).unwrap();
        let (out, _) = skin(&rows, &t, &rest, &centres);
        let columns: Vec<[DVec3; 4]> = t
            .iter()
            .map(|a| {
                [
                    a.matrix3.x_axis,
                    a.matrix3.y_axis,
                    a.matrix3.z_axis,
                    a.translation,
                ]
            })
            .collect();
        let rotations: Vec<DQuat> = t.iter().map(|a| rotation_quaternion(a.matrix3)).collect();
        for (v, &o) in out.iter().enumerate() {
            let (joints, weights) = w.row(v);
            let joints: Vec<u16> = joints.iter().map(|&j| j as u16).collect();
            let [c, d] = WorldCentredPoints {
                rest: &rest,
                centres: &centres,
            }
            .centre_and_offset(0, v);
            let expected = cor_point::<f64, _, false>(
                &joints,
                weights,
                w.heaviest(v).unwrap(),
                &[],
                &columns[..],
                &rotations,
                c,
                d,
            );
            assert_eq!(o, expected, "vertex {v}");
        }
    }
}
