//! Ω (`#V × #J`) in **count-sorted chunks**, the layout of every per-frame skinning kernel
//! ([`super::lbs_f32`], [`super::dqs`], [`super::cor`] and their f32 twins), generic over the
//! precision of the weights ([`SkinReal`]).
//!
//! Vertices are processed in chunks of [`VERTEX_GRAIN_F32`] (one rayon task each; a mesh of one
//! chunk is skinned serially on the calling thread, no dispatch). Inside a chunk they are stably
//! sorted by influence count, so a chunk is a few runs of equal count, each skinned by a loop with
//! a compile-time influence count (no per-vertex loop-exit misprediction; the measured gain on the
//! subdivided Arm is ≈ 2×). `local_index` maps a sorted slot back to its vertex in the chunk;
//! outputs are scattered back inside the chunk (an L2-resident window). A slot's global index is
//! `chunk · grain + position in the chunk`, so kernels can read per-vertex inputs either stored in
//! sorted order (by slot) or from the caller's arrays (by vertex).
//!
//! Joint indices are u16, the pivot (heaviest joint, DQS/CoR sign alignment) u16.
//! The f32 kernels store rest-space points relative to a local origin `o` (the bounding-box
//! centre of the rest mesh) so f32 coordinates stay small even far from the world origin; joint
//! transforms are converted to `T_j ∘ translate(o)` (in f64, then rounded) so kernels output
//! world coordinates.

use glam::{DAffine3, DVec3, Vec3A};
use rayon::prelude::*;

use super::precision::{RestPoint, SkinReal};
use crate::simd_dispatch::simd_dispatch;
use crate::{RigError, SkinWeights};

// Sorted slots index vertices within a chunk as u16.
/// Vertices per rayon task in the per-frame kernels (a mesh of at most this many vertices is
/// skinned serially).
pub(crate) const VERTEX_GRAIN_F32: usize = 8192;

const _: () = assert!(VERTEX_GRAIN_F32 <= 1 << 16);

/// A run of consecutive sorted slots of one chunk with the same influence count.
#[derive(Debug, Clone, Copy)]
struct Run {
    influences: u32,
    len: u32,
}

/// Vertices evaluated together by [`VertexKernel::skin_block`].
pub(crate) const BLOCK: usize = 8;

/// [`BLOCK`] consecutive sorted slots of one run, `K` influences each.
pub(crate) struct Block<'a, S> {
    /// `BLOCK · K` joints and weights, vertex by vertex.
    pub joints: &'a [u16],
    pub weights: &'a [S],
    /// `BLOCK` pivot joints.
    pub pivots: &'a [u16],
    /// Global slot of the first vertex.
    pub slot: usize,
    /// Global index of every vertex.
    pub vertices: [usize; BLOCK],
}

impl<S: SkinReal> Block<'_, S> {
    /// The block skinned vertex by vertex with `kernel.skin`.
    #[inline(always)]
    pub fn one_by_one<const K: usize>(
        &self,
        kernel: &(impl VertexKernel<S> + ?Sized),
    ) -> [S::V3; BLOCK] {
        std::array::from_fn(|l| {
            kernel.skin(
                &self.joints[l * K..(l + 1) * K],
                &self.weights[l * K..(l + 1) * K],
                self.pivots[l],
                self.slot + l,
                self.vertices[l],
            )
        })
    }

    /// Calls `f(lane, pivot, joint, weight)` for every influence, lane by lane.
    #[inline(always)]
    pub fn for_each_influence<const K: usize>(&self, mut f: impl FnMut(usize, usize, usize, S)) {
        for l in 0..BLOCK {
            let pivot = usize::from(self.pivots[l]);
            for k in 0..K {
                f(
                    l,
                    pivot,
                    usize::from(self.joints[l * K + k]),
                    self.weights[l * K + k],
                );
            }
        }
    }
}

/// Per-vertex skinning rule of a kernel, called by [`CountSortedWeights::skin`] with the
/// vertex's sorted `slot` and its index `vertex` (both global).
pub(crate) trait VertexKernel<S: SkinReal>: Sync {
    /// Position of a vertex with at least one influence (`joints`, `weights` of equal length).
    fn skin(&self, joints: &[u16], weights: &[S], pivot: u16, slot: usize, vertex: usize) -> S::V3;
    /// Positions of the vertices of `block` (`K` influences each), which a kernel may evaluate
    /// across SIMD lanes; by default one by one with [`Self::skin`].
    #[inline(always)]
    fn skin_block<const K: usize>(&self, block: &Block<'_, S>) -> [S::V3; BLOCK] {
        block.one_by_one::<K>(self)
    }
    /// Position of an unweighted vertex (its rest position).
    fn unweighted(&self, slot: usize, vertex: usize) -> S::V3;
}

/// Ω with weights in precision `S`, count-sorted within chunks, plus the per-vertex pivot joint.
#[derive(Debug, Clone)]
pub(crate) struct CountSortedWeights<S> {
    pub num_joints: usize,
    /// Vertex (within its chunk) of each sorted slot, `#V`.
    local_index: Vec<u16>,
    /// Runs of every chunk; chunk `c` owns `runs[run_start[c]..run_start[c + 1]]`.
    runs: Vec<Run>,
    run_start: Vec<u32>,
    /// First influence of every chunk in `joints` / `weights`.
    influence_start: Vec<u32>,
    joints: Vec<u16>,
    weights: Vec<S>,
    /// Heaviest joint per sorted slot (0 for unweighted vertices, unused there), `#V`.
    pivot: Vec<u16>,
    /// The (pivot, joint) pairs of the influences, as `pivot · #J + joint`, sorted, unique
    /// (for the sign table of [`super::antipodal_signs`]; empty above 256 joints).
    pub sign_pairs: Vec<u32>,
}

/// Skins one run of vertices with exactly `K` influences each; `first_slot`/`first_vertex` are
/// the run's first global slot and its chunk's first vertex.
#[inline(always)]
#[expect(clippy::too_many_arguments)]
fn skin_run<S: SkinReal, Kernel: VertexKernel<S>, const K: usize>(
    kernel: &Kernel,
    joints: &[u16],
    weights: &[S],
    pivots: &[u16],
    local_index: &[u16],
    first_slot: usize,
    first_vertex: usize,
    out: &mut [S::Out],
) {
    let blocks = pivots.len() / BLOCK;
    for b in 0..blocks {
        let base = b * BLOCK;
        let index = &local_index[base..base + BLOCK];
        let vertices: [usize; BLOCK] =
            std::array::from_fn(|l| first_vertex + usize::from(index[l]));
        let skinned = kernel.skin_block::<K>(&Block {
            joints: &joints[base * K..(base + BLOCK) * K],
            weights: &weights[base * K..(base + BLOCK) * K],
            pivots: &pivots[base..base + BLOCK],
            slot: first_slot + base,
            vertices,
        });
        for (&i, p) in index.iter().zip(skinned) {
            out[usize::from(i)] = S::output(p);
        }
    }
    let done = blocks * BLOCK;
    for (slot, (((js, ws), &pivot), &i)) in joints[done * K..]
        .chunks_exact(K)
        .zip(weights[done * K..].chunks_exact(K))
        .zip(&pivots[done..])
        .zip(&local_index[done..])
        .enumerate()
    {
        let i = usize::from(i);
        out[i] = S::output(kernel.skin(js, ws, pivot, first_slot + done + slot, first_vertex + i));
    }
}

impl<S: SkinReal> CountSortedWeights<S> {
    /// Ω (`#V × #J`; `#J` ≤ [`crate::skin_weights::MAX_JOINTS`], checked by [`SkinWeights`]).
    pub fn new(skin_weights: &SkinWeights) -> Self {
        let num_joints = skin_weights.num_joints();
        debug_assert!(num_joints <= crate::skin_weights::MAX_JOINTS);
        let num_vertices = skin_weights.num_vertices();
        let mut sorted = Self {
            num_joints,
            local_index: Vec::with_capacity(num_vertices),
            runs: Vec::new(),
            run_start: vec![0],
            influence_start: Vec::new(),
            joints: Vec::with_capacity(skin_weights.num_entries()),
            weights: Vec::with_capacity(skin_weights.num_entries()),
            pivot: Vec::with_capacity(num_vertices),
            sign_pairs: Vec::new(),
        };
        for first in (0..num_vertices).step_by(VERTEX_GRAIN_F32) {
            let last = (first + VERTEX_GRAIN_F32).min(num_vertices);
            let mut order: Vec<usize> = (first..last).collect();
            order.sort_by_key(|&v| skin_weights.row(v).0.len());
            sorted.influence_start.push(sorted.joints.len() as u32);
            let chunk_runs = sorted.runs.len();
            for &v in &order {
                let (joints, weights) = skin_weights.row(v);
                let k = joints.len() as u32;
                match sorted.runs[chunk_runs..].last_mut() {
                    Some(run) if run.influences == k => run.len += 1,
                    _ => sorted.runs.push(Run {
                        influences: k,
                        len: 1,
                    }),
                }
                sorted.local_index.push((v - first) as u16);
                sorted.joints.extend(joints.iter().map(|&j| j as u16));
                sorted
                    .weights
                    .extend(weights.iter().map(|&w| S::from_f64(w)));
                sorted
                    .pivot
                    .push(skin_weights.heaviest(v).unwrap_or(0) as u16);
            }
            sorted.run_start.push(sorted.runs.len() as u32);
        }
        if num_joints <= super::antipodal_signs::MAX_TABLE_JOINTS {
            let mut used = vec![false; num_joints * num_joints];
            for v in 0..num_vertices {
                if let Some(p) = skin_weights.heaviest(v) {
                    for &j in skin_weights.row(v).0 {
                        used[p * num_joints + j as usize] = true;
                    }
                }
            }
            sorted.sign_pairs = (0..used.len() as u32)
                .filter(|&i| used[i as usize])
                .collect();
        }
        sorted
    }

    pub fn num_vertices(&self) -> usize {
        self.local_index.len()
    }

    /// Fills `sorted[slot] = input(vertex of slot)` for every slot (parallel over chunks).
    pub fn gather<T: Send>(&self, sorted: &mut [T], input: impl Fn(usize) -> T + Sync) {
        assert_eq!(sorted.len(), self.num_vertices(), "sorted inputs");
        sorted
            .par_chunks_mut(VERTEX_GRAIN_F32)
            .zip(self.local_index.par_chunks(VERTEX_GRAIN_F32))
            .enumerate()
            .for_each(|(chunk, (sorted, local_index))| {
                let first = chunk * VERTEX_GRAIN_F32;
                for (o, &i) in sorted.iter_mut().zip(local_index) {
                    *o = input(first + usize::from(i));
                }
            });
    }

    /// `out[v] = kernel(v)` for every vertex (`#V`). One chunk runs on the calling thread; more
    /// run as one rayon task per chunk.
    pub fn skin<Kernel: VertexKernel<S>>(&self, kernel: &Kernel, out: &mut [S::Out]) {
        assert_eq!(out.len(), self.num_vertices(), "out");
        if out.len() <= VERTEX_GRAIN_F32 {
            if !out.is_empty() {
                self.skin_chunk(kernel, 0, out);
            }
            return;
        }
        out.par_chunks_mut(VERTEX_GRAIN_F32)
            .enumerate()
            .for_each(|(chunk, out)| self.skin_chunk(kernel, chunk, out));
    }

    simd_dispatch! {
        /// One chunk of [`Self::skin`], compiled for AVX2 where the CPU has it (wider registers
        /// and three-operand forms for the glam arithmetic; no fused multiply-add, so the results
        /// are the same on every path).
        fn skin_chunk[Kernel: VertexKernel<S>](
            &self,
            kernel: &Kernel,
            chunk: usize,
            out: &mut [S::Out],
        ) => Self::skin_chunk_generic;
        avx2: skin_chunk_avx2;
    }

    #[inline(always)]
    fn skin_chunk_generic<Kernel: VertexKernel<S>>(
        &self,
        kernel: &Kernel,
        chunk: usize,
        out: &mut [S::Out],
    ) {
        let first = chunk * VERTEX_GRAIN_F32;
        let local_index = &self.local_index[first..first + out.len()];
        let pivots = &self.pivot[first..first + out.len()];
        let runs = &self.runs[self.run_start[chunk] as usize..self.run_start[chunk + 1] as usize];
        let mut influence = self.influence_start[chunk] as usize;
        let mut slot = 0;
        for run in runs {
            let (k, len) = (run.influences as usize, run.len as usize);
            let j = &self.joints[influence..influence + k * len];
            let w = &self.weights[influence..influence + k * len];
            let p = &pivots[slot..slot + len];
            let i = &local_index[slot..slot + len];
            let s = first + slot;
            match k {
                0 => {
                    for (n, &i) in i.iter().enumerate() {
                        let i = usize::from(i);
                        out[i] = S::output(kernel.unweighted(s + n, first + i));
                    }
                }
                1 => skin_run::<S, Kernel, 1>(kernel, j, w, p, i, s, first, out),
                2 => skin_run::<S, Kernel, 2>(kernel, j, w, p, i, s, first, out),
                3 => skin_run::<S, Kernel, 3>(kernel, j, w, p, i, s, first, out),
                4 => skin_run::<S, Kernel, 4>(kernel, j, w, p, i, s, first, out),
                5 => skin_run::<S, Kernel, 5>(kernel, j, w, p, i, s, first, out),
                6 => skin_run::<S, Kernel, 6>(kernel, j, w, p, i, s, first, out),
                7 => skin_run::<S, Kernel, 7>(kernel, j, w, p, i, s, first, out),
                8 => skin_run::<S, Kernel, 8>(kernel, j, w, p, i, s, first, out),
                _ => {
                    for (n, (((js, ws), &pivot), &i)) in j
                        .chunks_exact(k)
                        .zip(w.chunks_exact(k))
                        .zip(p)
                        .zip(i)
                        .enumerate()
                    {
                        let i = usize::from(i);
                        out[i] = S::output(kernel.skin(js, ws, pivot, s + n, first + i));
                    }
                }
            }
            influence += k * len;
            slot += len;
        }
    }
}

/// Rest-space points a kernel reads per vertex: the stored sorted f32 copy (by slot, relative to
/// the local origin) or the caller's f64 array (by vertex, world coordinates).
pub(crate) trait RestPoints<S: SkinReal>: Sync {
    /// The point of `slot`/`vertex` in the kernel's space (local for f32, world for f64).
    fn point(&self, slot: usize, vertex: usize) -> S::V3;
    /// The same point in world coordinates.
    fn world(&self, slot: usize, vertex: usize) -> S::V3;
}

/// The caller's rest positions (`#V`, world, f64), read by vertex.
pub(crate) struct WorldPoints<'a>(pub &'a [DVec3]);

impl RestPoints<f64> for WorldPoints<'_> {
    #[inline(always)]
    fn point(&self, _slot: usize, vertex: usize) -> DVec3 {
        self.0[vertex]
    }
    #[inline(always)]
    fn world(&self, _slot: usize, vertex: usize) -> DVec3 {
        self.0[vertex]
    }
}

/// Stored local f32 points (`#V`, sorted order, `v − o`) and their origin `o`, read by slot.
pub(crate) struct LocalPoints<'a> {
    pub local: &'a [Vec3A],
    pub origin: Vec3A,
}

impl RestPoints<f32> for LocalPoints<'_> {
    #[inline(always)]
    fn point(&self, slot: usize, _vertex: usize) -> Vec3A {
        self.local[slot]
    }
    #[inline(always)]
    fn world(&self, slot: usize, _vertex: usize) -> Vec3A {
        self.local[slot] + self.origin
    }
}

/// Count-sorted Ω with the rest mesh M stored beside it, in sorted order, as f32 offsets from a
/// local origin `o` (the state shared by the f32 LBS and DQS kernels).
#[derive(Debug, Clone)]
pub(crate) struct SortedRestMesh {
    pub weights: CountSortedWeights<f32>,
    pub origin: DVec3,
    /// `v − o` per vertex, `#V`, sorted order.
    pub rest_local: Vec<Vec3A>,
    /// Names the kernel in size-mismatch errors.
    what: &'static str,
}

impl SortedRestMesh {
    /// `what` names the kernel in size-mismatch errors.
    pub fn new<P: RestPoint>(
        skin_weights: &SkinWeights,
        rest_positions: &[P],
        what: &'static str,
    ) -> Result<Self, RigError> {
        let weights = CountSortedWeights::new(skin_weights);
        let mut mesh = Self {
            rest_local: vec![Vec3A::ZERO; weights.num_vertices()],
            weights,
            origin: DVec3::ZERO,
            what,
        };
        mesh.set_rest_positions(rest_positions)?;
        Ok(mesh)
    }

    /// The stored points, read by slot.
    pub fn points(&self) -> LocalPoints<'_> {
        LocalPoints {
            local: &self.rest_local,
            origin: Vec3A::from(self.origin.as_vec3()),
        }
    }

    /// Replaces the stored rest mesh M (`#V`). Parallel, no allocation.
    pub fn set_rest_positions<P: RestPoint>(
        &mut self,
        rest_positions: &[P],
    ) -> Result<(), RigError> {
        if rest_positions.len() != self.weights.num_vertices() {
            return Err(RigError::SizeMismatch {
                what: self.what,
                expected: self.weights.num_vertices(),
                actual: rest_positions.len(),
            });
        }
        self.origin = local_origin(rest_positions);
        let origin = self.origin;
        self.weights.gather(&mut self.rest_local, |v| {
            Vec3A::from((rest_positions[v].to_f64() - origin).as_vec3())
        });
        Ok(())
    }
}

/// Local origin `o` of a point set: its bounding-box centre (zero when empty or non-finite).
pub(crate) fn local_origin<P: RestPoint>(points: &[P]) -> DVec3 {
    let empty = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    let grow = |(lo, hi): (DVec3, DVec3), p: &P| (lo.min(p.to_f64()), hi.max(p.to_f64()));
    let merge = |(lo, hi): (DVec3, DVec3), (l, h): (DVec3, DVec3)| (lo.min(l), hi.max(h));
    // In parallel beyond one chunk of vertices (min/max: the same result in any order).
    let (lo, hi) = if points.len() <= VERTEX_GRAIN_F32 {
        points.iter().fold(empty, grow)
    } else {
        points
            .par_chunks(VERTEX_GRAIN_F32)
            .map(|chunk| chunk.iter().fold(empty, grow))
            .reduce(|| empty, merge)
    };
    let centre = (lo + hi) * 0.5;
    if centre.is_finite() {
        centre
    } else {
        DVec3::ZERO
    }
}

/// Columns `[x_axis, y_axis, z_axis, translation]` of `T_j ∘ translate(o)` for every joint
/// (`#J`, computed in f64, then rounded to `S`): they map local rest coordinates `p − o` to
/// world coordinates.
pub(crate) fn columns_from_local<S: SkinReal>(
    transforms: &[DAffine3],
    origin: DVec3,
    columns: &mut [[S::V3; 4]],
) {
    assert_eq!(columns.len(), transforms.len(), "joint columns");
    let to_local = DAffine3::from_translation(origin);
    for (c, t) in columns.iter_mut().zip(transforms) {
        *c = S::affine_columns(&(*t * to_local));
    }
}

/// The affine maps `T_j` (`#J`) a kernel reads per influence, as columns
/// `[x_axis, y_axis, z_axis, translation]`.
pub(crate) trait JointColumns<S: SkinReal>: Sync {
    fn columns(&self, joint: usize) -> [S::V3; 4];
}

impl JointColumns<f64> for [DAffine3] {
    #[inline(always)]
    fn columns(&self, joint: usize) -> [DVec3; 4] {
        let a = &self[joint];
        [
            a.matrix3.x_axis,
            a.matrix3.y_axis,
            a.matrix3.z_axis,
            a.translation,
        ]
    }
}

impl<S: SkinReal> JointColumns<S> for [[S::V3; 4]] {
    #[inline(always)]
    fn columns(&self, joint: usize) -> [S::V3; 4] {
        self[joint]
    }
}
