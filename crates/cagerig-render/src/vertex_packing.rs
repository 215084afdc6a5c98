//! Packing a mesh layer's vertices (position, smooth normal, colour) for upload in one parallel
//! pass that also measures the layer's bounds, written straight into mapped staging memory (no
//! intermediate copy of the whole layer).

use bytemuck::Zeroable;
use glam::Vec3;

use crate::gpu_types::MeshVertex;
use crate::scene::{Bounds, EMPTY_BOUNDS, MeshPositions, merge_bounds};
use crate::vertex_normals::VertexNormals;

/// Vertices packed per local block before one copy into the destination (28 KiB, in L1/L2).
const BLOCK: usize = 1024;

/// Vertices per parallel task.
const GRAIN: usize = 16_384;

/// The vertex data of one mesh layer: positions (`#V`), optional per-vertex colours (`#V`) and
/// the vertex normals of this frame (face normals already computed), or none for flat shading.
#[derive(Clone, Copy)]
pub struct VertexSource<'a> {
    /// Vertex positions (world), `#V`.
    pub positions: MeshPositions<'a>,
    /// Per-vertex sRGB colours (`#V`); `None` = white.
    pub colors: Option<&'a [[u8; 4]]>,
    /// Vertex normals of this frame; `None` for flat shading.
    pub normals: Option<&'a VertexNormals>,
}

impl VertexSource<'_> {
    /// Number of vertices.
    pub fn len(&self) -> usize {
        self.positions.len()
    }

    /// Whether there are no vertices.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Vertex `i` at f32 `position` as uploaded: the position, the unnormalised smooth normal
    /// (the vertex shader normalises it; zero for flat shading or an isolated vertex), the sRGB
    /// colour (white when none).
    #[inline(always)]
    fn vertex_at(&self, i: usize, position: Vec3) -> MeshVertex {
        MeshVertex {
            position: position.to_array(),
            normal: self
                .normals
                .map_or([0.0; 3], |n| n.vertex_sum(i).to_array()),
            color: self.colors.map_or([255; 4], |c| c[i]),
        }
    }

    /// Packs every vertex into `out` (`#V`) and returns the bounds of the finite positions.
    pub fn pack_into(&self, out: &mut [MeshVertex]) -> Bounds {
        let bytes: &mut [u8] = bytemuck::cast_slice_mut(out);
        self.pack(wgpu::WriteOnly::from_mut(bytes), 0, self.len())
    }

    /// Packs vertices `first..first + count` into `dst` (`count` vertices of bytes) in parallel
    /// and returns the bounds of their finite positions.
    pub fn pack(&self, dst: wgpu::WriteOnly<'_, [u8]>, first: usize, count: usize) -> Bounds {
        if count > GRAIN {
            let half = (count / 2).next_multiple_of(BLOCK).min(count);
            let (a, b) = dst.split_at(half * size_of::<MeshVertex>());
            let (a, b) = (SendBytes(a), SendBytes(b));
            let (lo, hi) = rayon::join(
                move || self.pack(a.into_inner(), first, half),
                move || self.pack(b.into_inner(), first + half, count - half),
            );
            return merge_bounds(lo, hi);
        }
        match self.positions {
            MeshPositions::F64(p) => self.pack_serial(dst, first, count, |i| p[i].as_vec3()),
            MeshPositions::F32(p) => self.pack_serial(dst, first, count, |i| p[i]),
        }
    }

    /// [`VertexSource::pack`] on the calling thread, reading positions through `position`
    /// (one loop per precision). The bounds are taken of the f32 positions as uploaded.
    #[inline(always)]
    fn pack_serial(
        &self,
        dst: wgpu::WriteOnly<'_, [u8]>,
        first: usize,
        count: usize,
        position: impl Fn(usize) -> Vec3,
    ) -> Bounds {
        let (mut lo, mut hi) = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        let mut rest = dst;
        let mut block = [MeshVertex::zeroed(); BLOCK];
        let mut start = first;
        while start < first + count {
            let n = BLOCK.min(first + count - start);
            for (k, v) in block[..n].iter_mut().enumerate() {
                let i = start + k;
                let p = position(i);
                if p.is_finite() {
                    lo = lo.min(p);
                    hi = hi.max(p);
                }
                *v = self.vertex_at(i, p);
            }
            let (mut head, tail) = rest.split_at(n * size_of::<MeshVertex>());
            head.copy_from_slice(bytemuck::cast_slice(&block[..n]));
            rest = tail;
            start += n;
        }
        if lo.cmple(hi).all() {
            (lo.as_dvec3(), hi.as_dvec3())
        } else {
            EMPTY_BOUNDS
        }
    }
}

/// A write-only byte range handed to another rayon worker.
struct SendBytes<'a>(wgpu::WriteOnly<'a, [u8]>);

impl<'a> SendBytes<'a> {
    /// The range (a method, so that closures capture the whole `Send` wrapper).
    fn into_inner(self) -> wgpu::WriteOnly<'a, [u8]> {
        self.0
    }
}

#[expect(
    unsafe_code,
    reason = "a write-only byte borrow is as Send as &mut [u8]"
)]
// SAFETY: `WriteOnly<'a, [u8]>` is a unique, write-only borrow of `'a` bytes, like `&'a mut [u8]`,
// which is `Send`; wgpu implements `Send` for `WriteOnly<'_, T>` only for sized `T` (its impl has
// the implicit `T: Sized` bound), not because a byte slice could not be sent. The two halves of
// a `split_at` never overlap.
unsafe impl Send for SendBytes<'_> {}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    #[test]
    fn packing_matches_vertex_by_vertex_and_measures_the_bounds() {
        // More than one task and a partial last block.
        let n = 2 * GRAIN + BLOCK / 3;
        let positions: Vec<Vec3> = (0..n)
            .map(|i| Vec3::new(i as f32, -(i as f32) * 0.5, (i % 7) as f32))
            .collect();
        let triangles: Vec<[u32; 3]> = (0..n as u32 - 2).map(|i| [i, i + 1, i + 2]).collect();
        let mut normals = VertexNormals::new(n, &triangles);
        normals.face_normals(MeshPositions::F32(&positions), &triangles);
        let colors: Vec<[u8; 4]> = (0..n).map(|i| [i as u8, 0, 9, 255]).collect();
        let source = VertexSource {
            positions: MeshPositions::F32(&positions),
            colors: Some(&colors),
            normals: Some(&normals),
        };
        let mut out = vec![MeshVertex::zeroed(); n];
        let (lo, hi) = source.pack_into(&mut out);
        for (i, v) in out.iter().enumerate() {
            assert_eq!(*v, source.vertex_at(i, positions[i]), "vertex {i}");
        }
        assert_eq!(lo, DVec3::new(0.0, -((n - 1) as f64) * 0.5, 0.0));
        assert_eq!(hi, DVec3::new((n - 1) as f64, 0.0, 6.0));
        // Flat shading: zero normals, white when there are no colours; NaN points are skipped
        // by the bounds.
        let mut odd = positions.clone();
        odd[3] = Vec3::NAN;
        let flat = VertexSource {
            positions: MeshPositions::F32(&odd),
            colors: None,
            normals: None,
        };
        let (lo, _) = flat.pack_into(&mut out);
        assert_eq!(out[5].normal, [0.0; 3]);
        assert_eq!(out[5].color, [255; 4]);
        assert!(lo.is_finite());
    }
}
