//! Compact f32 copy of Ω (`#V × #J`) in **count-sorted chunks**, and the rest-space frame, shared
//! by the f32 per-frame skinning kernels ([`super::lbs_f32`], [`super::dqs_f32`],
//! [`super::cor_f32`]).
//!
//! Vertices are processed in chunks of [`VERTEX_GRAIN_F32`] (one rayon task each). Inside a chunk
//! they are stably sorted by influence count, so a chunk is a few runs of equal count, each skinned
//! by a loop with a compile-time influence count (no per-vertex loop-exit misprediction; the
//! measured gain on the subdivided Arm is ≈ 2×). `local_index` maps a sorted slot back to its
//! vertex in the chunk; every per-vertex kernel input is stored in sorted order and outputs are
//! scattered back inside the chunk (an L2-resident 96 KiB window).
//!
//! Joint indices are u16, weights f32, the pivot (heaviest joint, DQS/CoR sign alignment) u16.
//! Rest-space points are stored relative to a local origin `o` (the bounding-box centre of the
//! rest mesh) so f32 coordinates stay small even far from the world origin; joint transforms are
//! converted to `T_j ∘ translate(o)` (in f64, then rounded) so kernels output world coordinates.

use glam::{Affine3A, DAffine3, DVec3, Mat3A, Vec3, Vec3A};
use rayon::prelude::*;

use super::VERTEX_GRAIN_F32;
use crate::{RigError, SkinWeights};

// Sorted slots index vertices within a chunk as u16.
const _: () = assert!(VERTEX_GRAIN_F32 <= 1 << 16);

/// A run of consecutive sorted slots of one chunk with the same influence count.
#[derive(Debug, Clone, Copy)]
struct Run {
    influences: u32,
    len: u32,
}

/// Per-vertex skinning rule of an f32 kernel, called by [`CountSortedWeights::skin`].
pub(crate) trait VertexKernel: Sync {
    /// Per-vertex input stored in sorted order (e.g. the local rest position).
    type Input: Copy + Send + Sync;
    /// Position of a vertex with at least one influence (`joints`, `weights` of equal length).
    fn skin(&self, joints: &[u16], weights: &[f32], pivot: u16, input: Self::Input) -> Vec3A;
    /// Position of an unweighted vertex (its rest position).
    fn unweighted(&self, input: Self::Input) -> Vec3A;
}

/// Ω in f32, count-sorted within chunks, plus the per-vertex pivot joint.
#[derive(Debug, Clone)]
pub(crate) struct CountSortedWeights {
    pub num_joints: usize,
    /// Vertex (within its chunk) of each sorted slot, `#V`.
    local_index: Vec<u16>,
    /// Runs of every chunk; chunk `c` owns `runs[run_start[c]..run_start[c + 1]]`.
    runs: Vec<Run>,
    run_start: Vec<u32>,
    /// First influence of every chunk in `joints` / `weights`.
    influence_start: Vec<u32>,
    joints: Vec<u16>,
    weights: Vec<f32>,
    /// Heaviest joint per sorted slot (0 for unweighted vertices, unused there), `#V`.
    pivot: Vec<u16>,
}

/// Skins one run of vertices with exactly `K` influences each.
#[inline(always)]
fn skin_run<Kernel: VertexKernel, const K: usize>(
    kernel: &Kernel,
    joints: &[u16],
    weights: &[f32],
    pivots: &[u16],
    inputs: &[Kernel::Input],
    local_index: &[u16],
    out: &mut [Vec3],
) {
    for ((((js, ws), &pivot), &input), &i) in joints
        .chunks_exact(K)
        .zip(weights.chunks_exact(K))
        .zip(pivots)
        .zip(inputs)
        .zip(local_index)
    {
        out[usize::from(i)] = kernel.skin(js, ws, pivot, input).into();
    }
}

impl CountSortedWeights {
    /// Errors if `#J` exceeds 65 536 (u16 joint indices).
    pub fn new(skin_weights: &SkinWeights) -> Result<Self, RigError> {
        let num_joints = skin_weights.num_joints();
        if num_joints > usize::from(u16::MAX) + 1 {
            return Err(RigError::IndexOutOfRange {
                what: "joint count for u16 joint indices",
                index: num_joints,
                len: usize::from(u16::MAX) + 1,
            });
        }
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
                sorted.weights.extend(weights.iter().map(|&w| w as f32));
                sorted
                    .pivot
                    .push(skin_weights.heaviest(v).unwrap_or(0) as u16);
            }
            sorted.run_start.push(sorted.runs.len() as u32);
        }
        Ok(sorted)
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

    /// `out[v] = kernel(v)` for every vertex; `inputs` in sorted order (see [`Self::gather`]).
    pub fn skin<Kernel: VertexKernel>(
        &self,
        kernel: &Kernel,
        inputs: &[Kernel::Input],
        out: &mut [Vec3],
    ) {
        assert_eq!(inputs.len(), self.num_vertices(), "sorted inputs");
        assert_eq!(out.len(), self.num_vertices(), "out");
        out.par_chunks_mut(VERTEX_GRAIN_F32)
            .zip(inputs.par_chunks(VERTEX_GRAIN_F32))
            .zip(self.local_index.par_chunks(VERTEX_GRAIN_F32))
            .zip(self.pivot.par_chunks(VERTEX_GRAIN_F32))
            .enumerate()
            .for_each(|(chunk, (((out, inputs), local_index), pivots))| {
                self.skin_chunk(kernel, chunk, inputs, local_index, pivots, out)
            });
    }

    /// One chunk of [`Self::skin`], compiled for AVX2 where the CPU has it (wider registers and
    /// three-operand forms for the glam SSE arithmetic; no fused multiply-add, so the results
    /// are the same on every path).
    fn skin_chunk<Kernel: VertexKernel>(
        &self,
        kernel: &Kernel,
        chunk: usize,
        inputs: &[Kernel::Input],
        local_index: &[u16],
        pivots: &[u16],
        out: &mut [Vec3],
    ) {
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") {
                // SAFETY: the CPU supports the enabled feature (checked just above).
                return unsafe {
                    self.skin_chunk_avx2(kernel, chunk, inputs, local_index, pivots, out)
                };
            }
        }
        self.skin_chunk_generic(kernel, chunk, inputs, local_index, pivots, out)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    fn skin_chunk_avx2<Kernel: VertexKernel>(
        &self,
        kernel: &Kernel,
        chunk: usize,
        inputs: &[Kernel::Input],
        local_index: &[u16],
        pivots: &[u16],
        out: &mut [Vec3],
    ) {
        self.skin_chunk_generic(kernel, chunk, inputs, local_index, pivots, out)
    }

    #[inline(always)]
    fn skin_chunk_generic<Kernel: VertexKernel>(
        &self,
        kernel: &Kernel,
        chunk: usize,
        inputs: &[Kernel::Input],
        local_index: &[u16],
        pivots: &[u16],
        out: &mut [Vec3],
    ) {
        let runs = &self.runs[self.run_start[chunk] as usize..self.run_start[chunk + 1] as usize];
        let mut influence = self.influence_start[chunk] as usize;
        let mut slot = 0;
        for run in runs {
            let (k, len) = (run.influences as usize, run.len as usize);
            let j = &self.joints[influence..influence + k * len];
            let w = &self.weights[influence..influence + k * len];
            let p = &pivots[slot..slot + len];
            let x = &inputs[slot..slot + len];
            let i = &local_index[slot..slot + len];
            match k {
                0 => {
                    for (&x, &i) in x.iter().zip(i) {
                        out[usize::from(i)] = kernel.unweighted(x).into();
                    }
                }
                1 => skin_run::<Kernel, 1>(kernel, j, w, p, x, i, out),
                2 => skin_run::<Kernel, 2>(kernel, j, w, p, x, i, out),
                3 => skin_run::<Kernel, 3>(kernel, j, w, p, x, i, out),
                4 => skin_run::<Kernel, 4>(kernel, j, w, p, x, i, out),
                5 => skin_run::<Kernel, 5>(kernel, j, w, p, x, i, out),
                6 => skin_run::<Kernel, 6>(kernel, j, w, p, x, i, out),
                7 => skin_run::<Kernel, 7>(kernel, j, w, p, x, i, out),
                8 => skin_run::<Kernel, 8>(kernel, j, w, p, x, i, out),
                _ => {
                    for ((((js, ws), &pivot), &x), &i) in j
                        .chunks_exact(k)
                        .zip(w.chunks_exact(k))
                        .zip(p)
                        .zip(x)
                        .zip(i)
                    {
                        out[usize::from(i)] = kernel.skin(js, ws, pivot, x).into();
                    }
                }
            }
            influence += k * len;
            slot += len;
        }
    }
}

/// Count-sorted Ω with the rest mesh M stored beside it, in sorted order, as f32 offsets from a
/// local origin `o` (the state shared by the f32 LBS and DQS kernels).
#[derive(Debug, Clone)]
pub(crate) struct SortedRestMesh {
    pub weights: CountSortedWeights,
    pub origin: DVec3,
    /// `v − o` per vertex, `#V`, sorted order.
    pub rest_local: Vec<Vec3A>,
    /// Names the kernel in size-mismatch errors.
    what: &'static str,
}

impl SortedRestMesh {
    /// `what` names the kernel in size-mismatch errors.
    pub fn new(
        skin_weights: &SkinWeights,
        rest_positions: &[DVec3],
        what: &'static str,
    ) -> Result<Self, RigError> {
        let weights = CountSortedWeights::new(skin_weights)?;
        let mut mesh = Self {
            rest_local: vec![Vec3A::ZERO; weights.num_vertices()],
            weights,
            origin: DVec3::ZERO,
            what,
        };
        mesh.set_rest_positions(rest_positions)?;
        Ok(mesh)
    }

    /// Replaces the stored rest mesh M (`#V`). Parallel, no allocation.
    pub fn set_rest_positions(&mut self, rest_positions: &[DVec3]) -> Result<(), RigError> {
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
            Vec3A::from((rest_positions[v] - origin).as_vec3())
        });
        Ok(())
    }
}

/// Local origin `o` of a point set: its bounding-box centre (zero when empty or non-finite).
pub(crate) fn local_origin(points: &[DVec3]) -> DVec3 {
    let (lo, hi) = crate::mesh::bounding_box(points);
    let centre = (lo + hi) * 0.5;
    if centre.is_finite() {
        centre
    } else {
        DVec3::ZERO
    }
}

/// `T ∘ translate(o)` rounded to f32: maps local rest coordinates `p − o` to world coordinates.
pub(crate) fn affine_from_local(transform: &DAffine3, origin: DVec3) -> Affine3A {
    let m = transform.matrix3;
    Affine3A {
        matrix3: Mat3A::from_cols(
            m.x_axis.as_vec3().into(),
            m.y_axis.as_vec3().into(),
            m.z_axis.as_vec3().into(),
        ),
        translation: Vec3A::from(transform.transform_point3(origin).as_vec3()),
    }
}
