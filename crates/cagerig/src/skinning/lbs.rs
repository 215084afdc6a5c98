//! Linear blend skinning (Eq. 2–3): `v'_i = (Σ_j ω_ij T_j^r)·v_i + Σ_j ω_ij T_j^t`.

use glam::{DAffine3, DMat3, DVec3};

use rayon::prelude::*;

use super::compact_weights::VERTEX_GRAIN_F32;
use super::compact_weights::{JointColumns, RestPoints, VertexKernel};
use super::precision::SkinReal;
use crate::simd_dispatch::simd_dispatch;
use crate::{RigError, SkinWeights};

/// Precomputed LBS: Ω (`#V × #J`) as flat CSR rows, streamed in vertex order by
/// [`LinearBlendSkinning::apply`] (LBS is memory-bound: sequential rows beat the count-sorted
/// layout of the DQS/CoR kernels here, 0.6 against 1.4 ms at 133k vertices) and read per vertex
/// by CageUp/CageRev.
#[derive(Debug, Clone)]
pub struct LinearBlendSkinning {
    num_joints: usize,
    row_start: Vec<u32>,
    /// Joint indices as u16 (≤ [`crate::skin_weights::MAX_JOINTS`]), as the generic rule takes.
    joints: Vec<u16>,
    weights: Vec<f64>,
}

/// Columns `[x, y, z, t]` of `Σ_j ω_j T_j` (Eq. 2–3) in precision `S`, accumulated in influence
/// order.
#[inline(always)]
pub(crate) fn blend_columns<S: SkinReal, T: JointColumns<S> + ?Sized>(
    joints: &[u16],
    weights: &[S],
    transforms: &T,
) -> [S::V3; 4] {
    let mut blended = [S::ZERO_V3; 4];
    for (&j, &w) in joints.iter().zip(weights) {
        let a = transforms.columns(usize::from(j));
        for (b, x) in blended.iter_mut().zip(a) {
            *b = *b + x * w;
        }
    }
    blended
}

/// `((x p.x + y p.y) + z p.z) + t` for affine columns `[x, y, z, t]`.
#[inline(always)]
pub(crate) fn transform_point<S: SkinReal>(columns: &[S::V3; 4], p: S::V3) -> S::V3 {
    let [px, py, pz] = S::components(p);
    columns[0] * px + columns[1] * py + columns[2] * pz + columns[3]
}

/// The per-vertex LBS rule (Eq. 2–3) for a kernel of precision `S`.
pub(crate) struct LbsRule<'a, T: ?Sized, P> {
    pub transforms: &'a T,
    pub points: P,
}

impl<S: SkinReal, T: JointColumns<S> + ?Sized, P: RestPoints<S>> VertexKernel<S>
    for LbsRule<'_, T, P>
{
    #[inline(always)]
    fn skin(
        &self,
        joints: &[u16],
        weights: &[S],
        _pivot: u16,
        slot: usize,
        vertex: usize,
    ) -> S::V3 {
        transform_point::<S>(
            &blend_columns(joints, weights, self.transforms),
            self.points.point(slot, vertex),
        )
    }

    #[inline(always)]
    fn unweighted(&self, slot: usize, vertex: usize) -> S::V3 {
        self.points.world(slot, vertex)
    }
}

impl LinearBlendSkinning {
    /// Precomputes the kernel from Ω (`#V × #J`).
    pub fn new(weights: &SkinWeights) -> Self {
        let (row_start, joints, w) = weights.csr();
        Self {
            num_joints: weights.num_joints(),
            row_start: row_start.to_vec(),
            joints: joints.iter().map(|&j| j as u16).collect(),
            weights: w.to_vec(),
        }
    }

    /// Number of mesh vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.row_start.len() - 1
    }

    /// Number of joints `#J`.
    pub fn num_joints(&self) -> usize {
        self.num_joints
    }

    #[inline(always)]
    fn row(&self, v: usize) -> (&[u16], &[f64]) {
        let range = self.row_start[v] as usize..self.row_start[v + 1] as usize;
        (&self.joints[range.clone()], &self.weights[range])
    }

    /// Skins vertex `v` at rest position `rest` (unweighted vertices stay at rest).
    #[inline(always)]
    fn skin_vertex(&self, v: usize, transforms: &[DAffine3], rest: DVec3) -> DVec3 {
        let (joints, weights) = self.row(v);
        if joints.is_empty() {
            return rest;
        }
        transform_point::<f64>(&blend_columns(joints, weights, transforms), rest)
    }

    /// M' = LBS(T, Ω, M) (Eq. 2–3). `transforms`: `#J`; `rest_positions`, `out`: `#V`.
    /// Bit-identical to [`Self::apply_rows`] on every vertex.
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn apply(&self, transforms: &[DAffine3], rest_positions: &[DVec3], out: &mut [DVec3]) {
        assert_eq!(transforms.len(), self.num_joints, "LBS: transforms");
        assert_eq!(rest_positions.len(), self.num_vertices(), "LBS: rest");
        assert_eq!(out.len(), self.num_vertices(), "LBS: out");
        let skin_chunk = |chunk: usize, out: &mut [DVec3]| {
            let first = chunk * VERTEX_GRAIN_F32;
            let rest = &rest_positions[first..first + out.len()];
            self.skin_range(first, transforms, rest, out);
        };
        if out.len() <= VERTEX_GRAIN_F32 {
            skin_chunk(0, out);
        } else {
            out.par_chunks_mut(VERTEX_GRAIN_F32)
                .enumerate()
                .for_each(|(chunk, out)| skin_chunk(chunk, out));
        }
    }

    /// M' = LBS(T, Ω, M) on the vertices `first..first + out.len()` (`rest_positions` holding
    /// their M): the bits of those rows of [`Self::apply`], serial. A tiled product of M calls
    /// it on each tile while the tile is in cache (`CageCoords::apply_then`).
    ///
    /// # Panics
    /// If `transforms` is not `#J` long, the two slices differ in length or the range passes
    /// `#V`.
    pub fn apply_range(
        &self,
        transforms: &[DAffine3],
        first: usize,
        rest_positions: &[DVec3],
        out: &mut [DVec3],
    ) {
        assert_eq!(transforms.len(), self.num_joints, "LBS: transforms");
        assert_eq!(rest_positions.len(), out.len(), "LBS: rest rows");
        assert!(
            first + out.len() <= self.num_vertices(),
            "LBS: rows past #V"
        );
        self.skin_range(first, transforms, rest_positions, out);
    }

    simd_dispatch! {
        /// `out[i] = LBS(first + i)` at rest position `rest[i]`, compiled for AVX2 where the CPU
        /// has it (wider registers and three-operand forms for the glam arithmetic; no fused
        /// multiply-add, so the same bits as the baseline code).
        fn skin_range(
            &self,
            first: usize,
            transforms: &[DAffine3],
            rest: &[DVec3],
            out: &mut [DVec3],
        ) => Self::skin_range_generic;
        avx2: skin_range_avx2;
    }

    #[inline(always)]
    fn skin_range_generic(
        &self,
        first: usize,
        transforms: &[DAffine3],
        rest: &[DVec3],
        out: &mut [DVec3],
    ) {
        for (i, (o, &p)) in out.iter_mut().zip(rest).enumerate() {
            *o = self.skin_vertex(first + i, transforms, p);
        }
    }

    /// LBS of a subset of vertices (e.g. the MaxVol rows of the ghost mesh used by CageUp):
    /// `out[k] = LBS(rows[k])` with rest position `rest_positions_of_rows[k]`. Serial (the subset
    /// is small).
    ///
    /// # Panics
    /// If the slice lengths differ or a row is out of range.
    pub fn apply_rows(
        &self,
        rows: &[usize],
        transforms: &[DAffine3],
        rest_positions_of_rows: &[DVec3],
        out: &mut [DVec3],
    ) {
        assert_eq!(transforms.len(), self.num_joints, "LBS: transforms");
        assert_eq!(rows.len(), rest_positions_of_rows.len(), "LBS: rest rows");
        assert_eq!(rows.len(), out.len(), "LBS: out rows");
        for ((o, &v), &p) in out.iter_mut().zip(rows).zip(rest_positions_of_rows) {
            *o = self.skin_vertex(v, transforms, p);
        }
    }

    /// Blended linear part `R(i) = Σ_j ω_ij T_j^r` of vertex `v` (the diagonal blocks of ℛ in
    /// Eq. 15, used by CageRev). Zero for an unweighted vertex.
    pub fn blended_linear_part(&self, v: usize, transforms: &[DAffine3]) -> DMat3 {
        let (joints, weights) = self.row(v);
        let [x, y, z, _] = blend_columns(joints, weights, transforms);
        DMat3::from_cols(x, y, z)
    }

    /// The rest points whose LBS is `posed` (Eq. 2–3 solved per vertex):
    /// `x_v = R_v⁻¹·(y_v − t_v)`, with `R_v = Σ_j ω_vj T_j^r` and `t_v = Σ_j ω_vj T_j^t`. What a
    /// host that skins with LBS only (Blender's Armature modifier) needs to show another
    /// method's M' = y: a corrective shape holding x. An unweighted vertex keeps `y_v`.
    /// `transforms`: `#J`; `posed`, `out`: `#V`. Parallel, no allocation.
    ///
    /// # Errors
    /// [`RigError::SingularBlend`] for the first vertex whose `R_v` is singular
    /// (`|det R_v| ≤ 1e-12·‖R_v‖³`, e.g. a half-half blend of opposite rotations).
    ///
    /// # Panics
    /// If a slice length does not match `#J` / `#V`.
    pub fn rest_preimage(
        &self,
        transforms: &[DAffine3],
        posed: &[DVec3],
        out: &mut [DVec3],
    ) -> Result<(), RigError> {
        assert_eq!(
            transforms.len(),
            self.num_joints,
            "LBS preimage: transforms"
        );
        assert_eq!(posed.len(), self.num_vertices(), "LBS preimage: posed");
        assert_eq!(out.len(), self.num_vertices(), "LBS preimage: out");
        out.par_chunks_mut(VERTEX_GRAIN_F32)
            .enumerate()
            .try_for_each(|(chunk, out)| {
                let first = chunk * VERTEX_GRAIN_F32;
                for (offset, x) in out.iter_mut().enumerate() {
                    let v = first + offset;
                    let (joints, weights) = self.row(v);
                    if joints.is_empty() {
                        *x = posed[v];
                        continue;
                    }
                    let [c0, c1, c2, t] = blend_columns::<f64, _>(joints, weights, transforms);
                    let linear = DMat3::from_cols(c0, c1, c2);
                    let determinant = linear.determinant();
                    let scale = c0.length().max(c1.length()).max(c2.length());
                    if determinant.abs() <= 1e-12 * scale * scale * scale
                        || !determinant.is_finite()
                    {
                        return Err(RigError::SingularBlend {
                            vertex: v,
                            determinant,
                        });
                    }
                    *x = linear.inverse() * (posed[v] - t);
                }
                Ok(())
            })
    }

    /// Blended translation `Σ_j ω_ij T_j^t` of vertex `v` (Eq. 3).
    pub fn blended_translation(&self, v: usize, transforms: &[DAffine3]) -> DVec3 {
        let (joints, weights) = self.row(v);
        blend_columns(joints, weights, transforms)[3]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_PI_2;

    fn about(point: DVec3, rotation: DAffine3) -> DAffine3 {
        DAffine3::from_translation(point) * rotation * DAffine3::from_translation(-point)
    }

    #[test]
    fn the_rest_preimage_skins_back_to_the_posed_points_and_a_singular_blend_is_named() {
        let (w, _) =
            SkinWeights::from_dense(&[vec![1.0, 0.0], vec![0.3, 0.7], vec![0.0, 0.0]]).unwrap();
        let lbs = LinearBlendSkinning::new(&w);
        let t = [
            about(DVec3::new(1.0, 2.0, 0.0), DAffine3::from_rotation_z(0.4)),
            DAffine3::from_scale_rotation_translation(
                DVec3::splat(1.5),
                glam::DQuat::from_rotation_x(-0.9),
                DVec3::new(0.5, -1.0, 2.0),
            ),
        ];
        let posed = [
            DVec3::new(3.0, -1.0, 2.0),
            DVec3::new(-2.0, 0.5, 1.0),
            DVec3::new(7.0, 8.0, 9.0),
        ];
        let mut rest = [DVec3::ZERO; 3];
        lbs.rest_preimage(&t, &posed, &mut rest).unwrap();
        let mut back = [DVec3::ZERO; 3];
        lbs.apply(&t, &rest, &mut back);
        for (b, p) in back.iter().zip(&posed) {
            assert!(b.abs_diff_eq(*p, 1e-12), "{back:?} vs {posed:?}");
        }
        assert_eq!(rest[2], posed[2], "an unweighted vertex stays");
        // Half of +90° and half of −90° about x: the blend flattens y and z to zero.
        let (w, _) = SkinWeights::from_dense(&[vec![0.5, 0.5]]).unwrap();
        let twist = [
            DAffine3::from_rotation_x(FRAC_PI_2 * 2.0),
            DAffine3::IDENTITY,
        ];
        let error = LinearBlendSkinning::new(&w)
            .rest_preimage(&twist, &[DVec3::X], &mut [DVec3::ZERO])
            .unwrap_err();
        assert!(
            matches!(error, RigError::SingularBlend { vertex: 0, .. }),
            "{error}"
        );
    }

    #[test]
    fn single_bone_rotation_about_a_point() {
        let (w, _) = SkinWeights::from_dense(&[vec![1.0], vec![1.0]]).unwrap();
        let lbs = LinearBlendSkinning::new(&w);
        let pivot = DVec3::new(1.0, 0.0, 0.0);
        let t = [about(pivot, DAffine3::from_rotation_z(FRAC_PI_2))];
        let rest = [DVec3::new(2.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 3.0)];
        let mut out = [DVec3::ZERO; 2];
        lbs.apply(&t, &rest, &mut out);
        assert!(out[0].abs_diff_eq(DVec3::new(1.0, 1.0, 0.0), 1e-15));
        assert!(out[1].abs_diff_eq(DVec3::new(1.0, 0.0, 3.0), 1e-15));
    }

    #[test]
    fn half_half_plus_minus_90_degrees_collapses() {
        // Twisting ±90° about x: the blended linear part is diag(1, 0, 0) (candy wrapper).
        let (w, _) = SkinWeights::from_dense(&[vec![0.5, 0.5]]).unwrap();
        let lbs = LinearBlendSkinning::new(&w);
        let t = [
            DAffine3::from_rotation_x(FRAC_PI_2),
            DAffine3::from_rotation_x(-FRAC_PI_2),
        ];
        let mut out = [DVec3::ZERO];
        lbs.apply(&t, &[DVec3::new(3.0, 1.0, 2.0)], &mut out);
        assert!(out[0].abs_diff_eq(DVec3::new(3.0, 0.0, 0.0), 1e-15));
        let r = lbs.blended_linear_part(0, &t);
        assert!(r.abs_diff_eq(DMat3::from_diagonal(DVec3::new(1.0, 0.0, 0.0)), 1e-15));
        // apply_rows agrees with apply.
        let mut sub = [DVec3::ZERO];
        lbs.apply_rows(&[0], &t, &[DVec3::new(3.0, 1.0, 2.0)], &mut sub);
        assert_eq!(sub, out);
    }

    /// `apply` runs code compiled for AVX2 (where the CPU has it), `apply_rows` the baseline
    /// code: the same bits on every vertex, over several parallel chunks, rows of 0 to 4
    /// influences and general affine transforms.
    #[test]
    fn apply_and_apply_rows_give_the_same_bits() {
        let mut unit = crate::test_random::uniform(0x853c_49e6_748f_ea9bu64);
        let mut random = move || unit() - 0.5;
        let (nv, nj) = (3 * VERTEX_GRAIN_F32 + 17, 6);
        let mut triplets = Vec::new();
        for v in 0..nv {
            for k in 0..v % 5 {
                // Distinct joints: rows of 0 to 4 influences.
                triplets.push((v, (v + k) % nj, random() + 0.6));
            }
        }
        let (w, _) = SkinWeights::from_triplets(nv, nj, triplets).unwrap();
        let lbs = LinearBlendSkinning::new(&w);
        let t: Vec<DAffine3> = (0..nj)
            .map(|_| DAffine3::from_cols_array(&std::array::from_fn(|_| random() * 3.0)))
            .collect();
        let rest: Vec<DVec3> = (0..nv)
            .map(|_| DVec3::new(random(), random(), random()) * 10.0)
            .collect();
        let mut all = vec![DVec3::ZERO; nv];
        lbs.apply(&t, &rest, &mut all);
        let rows: Vec<usize> = (0..nv).collect();
        let mut by_rows = vec![DVec3::ZERO; nv];
        lbs.apply_rows(&rows, &t, &rest, &mut by_rows);
        assert_eq!(all, by_rows);
        // By ranges of any length, as a tiled product hands them on: the same bits.
        let mut by_ranges = vec![DVec3::NAN; nv];
        let mut first = 0;
        for len in [1, 7, 1000, VERTEX_GRAIN_F32 + 3].into_iter().cycle() {
            let end = (first + len).min(nv);
            lbs.apply_range(&t, first, &rest[first..end], &mut by_ranges[first..end]);
            first = end;
            if first == nv {
                break;
            }
        }
        assert_eq!(all, by_ranges);
    }

    #[test]
    fn unweighted_vertex_stays_at_rest() {
        let (w, _) = SkinWeights::from_triplets(2, 1, [(0, 0, 1.0)]).unwrap();
        let lbs = LinearBlendSkinning::new(&w);
        let t = [DAffine3::from_translation(DVec3::X)];
        let mut out = [DVec3::ZERO; 2];
        lbs.apply(&t, &[DVec3::Y, DVec3::Z], &mut out);
        assert_eq!(out, [DVec3::new(1.0, 1.0, 0.0), DVec3::Z]);
    }
}
