//! Mean value coordinates (Ju, Schaefer & Warren 2005) of points w.r.t. a triangle mesh.
//!
//! Used for the cage coordinates Φ (`#V × #C`, Eq. 7: mesh vertex i = Σ_k Φ[i,k] C_k) and for
//! the MVC prior of a joint w.r.t. the (possibly open) character mesh in SkelUp.
//!
//! Formulation: per point x, with `d_k = |p_k − x|` and `u_k = (p_k − x)/d_k`, every triangle
//! T = (i0, i1, i2) contributes its mean vector `m_T = Σ_e (θ_e / 2) n_e` (θ_e the arc length of
//! edge e on the unit sphere, n_e the normal of the plane through x and e) expressed in the basis
//! u_i0, u_i1, u_i2: `λ_j = (c_j · m_T) / det(u_i0, u_i1, u_i2)` with `c_j = u_{j+1} × u_{j+2}`,
//! and `w_{i_j} += λ_j / d_{i_j}`; finally w is normalised to sum to 1. This is algebraically the
//! same as Ju et al.'s trigonometric formula but needs one `atan2` per *edge* (edges are shared
//! by two triangles) and no other transcendental function.
//!
//! Degenerate positions (exact limits of the coordinates):
//! - within `1e-8 · max_k d_k` of a cage vertex: that vertex gets weight 1;
//! - on an edge (`|u_a × u_b| < 1e-8` with `u_a · u_b < 0`): linear interpolation along the edge;
//! - on a triangle's plane (`|det| < 1e-8`) inside the triangle: planar barycentric coordinates;
//!   outside the triangle: the triangle is skipped (its contribution tends to zero there).
//!
//! Points outside the cage are supported (MVC are defined everywhere off the surface; weights may
//! be negative). Closedness is not required by the per-point functions.

#![expect(
    unsafe_code,
    reason = "Φ filled by disjoint row blocks without a zero fill (row_blocks)"
)]

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;

use super::mvc_batch::{BatchScratch, evaluate_rows};
use super::mvc_triangle::{
    Contribution, EdgeTerms, edge_terms, normalise, snapped_vertex, triangle_contribution,
    write_on_edge, write_on_triangle,
};
pub(crate) use super::mvc_triangle::{TriangleWeights, triangle_weights};
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::row_blocks::{BlockProgress, fill_by_row_blocks};

/// Dimensionless tolerance for the degenerate cases (same value as Ju et al.'s reference code).
pub(crate) const EPS: f64 = 1e-8;

/// Points handled per parallel task by [`compute_cage_coords`].
const POINT_BLOCK: usize = 256;

/// Mean value coordinates of `point` w.r.t. the mesh (`cage_positions` `#C`, `cage_triangles`
/// `#F`), written into `out` (`#C`, sums to 1). Allocation-free: computes everything per
/// triangle (one `atan2` per triangle corner). For many points use [`MvcEvaluator`], which
/// shares the per-vertex and per-edge work.
///
/// If the weights cannot be normalised (all triangles degenerate or a zero total, only possible
/// for open meshes seen edge-on), `out` is filled with NaN.
pub fn mean_value_coordinates(
    cage_positions: &[DVec3],
    cage_triangles: &[[u32; 3]],
    point: DVec3,
    out: &mut [f64],
) {
    debug_assert_eq!(out.len(), cage_positions.len());
    out.iter_mut().for_each(|w| *w = 0.0);
    if let Some(k) = snapped_vertex(cage_positions, point) {
        out[k] = 1.0;
        return;
    }
    for tri in cage_triangles {
        let idx = tri.map(|i| i as usize);
        match triangle_weights(cage_positions, *tri, point) {
            TriangleWeights::Add(w) => {
                for j in 0..3 {
                    out[idx[j]] += w[j];
                }
            }
            TriangleWeights::Skip => {}
            TriangleWeights::OnEdge {
                a,
                b,
                dist_a,
                dist_b,
            } => {
                write_on_edge(a, b, dist_a, dist_b, out);
                return;
            }
            TriangleWeights::OnTriangle => {
                write_on_triangle(cage_positions, idx, point, out);
                return;
            }
        }
    }
    normalise(out);
}

/// Precomputed edge topology of a mesh for evaluating MVC at many points
/// ([`MvcEvaluator::evaluate`] shares the `atan2` of each edge between its triangles).
#[derive(Debug, Clone)]
pub struct MvcEvaluator<'a> {
    pub(crate) positions: &'a [DVec3],
    pub(crate) triangles: &'a [[u32; 3]],
    /// Unique undirected edges `(a, b)`, `a < b`, `#E`.
    pub(crate) edges: Vec<[u32; 2]>,
    /// Per triangle, per corner j: the edge opposite j (`(j+1, j+2)`) and whether it is stored
    /// reversed (`a > b` in triangle order), `#F`.
    pub(crate) triangle_edges: Vec<[(u32, bool); 3]>,
}

/// Per-thread scratch for [`MvcEvaluator::evaluate`]: per-vertex unit vectors and distances and
/// per-edge terms. Allocate once per thread with [`MvcEvaluator::scratch`].
#[derive(Debug, Clone)]
pub struct MvcScratch {
    unit: Vec<DVec3>,
    dist: Vec<f64>,
    edge_cross: Vec<DVec3>,
    edge_k: Vec<f64>,
    edge_theta: Vec<f64>,
}

impl<'a> MvcEvaluator<'a> {
    /// Builds the edge list. Indices must be in range (as guaranteed by [`TriMesh::new`]).
    pub fn new(positions: &'a [DVec3], triangles: &'a [[u32; 3]]) -> Self {
        let mut directed: Vec<(u32, u32, usize, usize)> = Vec::with_capacity(triangles.len() * 3);
        for (t, tri) in triangles.iter().enumerate() {
            for j in 0..3 {
                let (a, b) = (tri[(j + 1) % 3], tri[(j + 2) % 3]);
                directed.push((a.min(b), a.max(b), t, j));
            }
        }
        directed.sort_unstable();
        let mut edges: Vec<[u32; 2]> = Vec::new();
        let mut triangle_edges = vec![[(0u32, false); 3]; triangles.len()];
        for &(a, b, t, j) in &directed {
            if edges.last() != Some(&[a, b]) {
                edges.push([a, b]);
            }
            let tri = triangles[t];
            let reversed = tri[(j + 1) % 3] != a;
            triangle_edges[t][j] = ((edges.len() - 1) as u32, reversed);
        }
        Self {
            positions,
            triangles,
            edges,
            triangle_edges,
        }
    }

    /// Number of vertices of the cage mesh (`#C`: the length of a coordinate row).
    pub fn num_vertices(&self) -> usize {
        self.positions.len()
    }

    /// A scratch buffer sized for this mesh.
    pub fn scratch(&self) -> MvcScratch {
        MvcScratch {
            unit: vec![DVec3::ZERO; self.positions.len()],
            dist: vec![0.0; self.positions.len()],
            edge_cross: vec![DVec3::ZERO; self.edges.len()],
            edge_k: vec![0.0; self.edges.len()],
            edge_theta: vec![0.0; self.edges.len()],
        }
    }

    /// Same result as [`mean_value_coordinates`] (to rounding), without allocation.
    /// `out` is `#C`.
    pub fn evaluate(&self, point: DVec3, scratch: &mut MvcScratch, out: &mut [f64]) {
        debug_assert_eq!(out.len(), self.positions.len());
        out.iter_mut().for_each(|w| *w = 0.0);
        let mut nearest = (0, f64::INFINITY);
        let mut farthest: f64 = 0.0;
        for (k, ((p, u), d)) in self
            .positions
            .iter()
            .zip(scratch.unit.iter_mut())
            .zip(scratch.dist.iter_mut())
            .enumerate()
        {
            let v = *p - point;
            *d = v.length();
            *u = v / *d;
            if *d < nearest.1 {
                nearest = (k, *d);
            }
            farthest = farthest.max(*d);
        }
        // Same test as `snapped_vertex`.
        if nearest.1 <= EPS * farthest {
            out[nearest.0] = 1.0;
            return;
        }
        for (e, &[a, b]) in self.edges.iter().enumerate() {
            let (a, b) = (a as usize, b as usize);
            match edge_terms(scratch.unit[a], scratch.unit[b]) {
                EdgeTerms::Regular { c, k, angle } => {
                    scratch.edge_cross[e] = c;
                    scratch.edge_k[e] = k;
                    scratch.edge_theta[e] = angle;
                }
                EdgeTerms::OnEdge => {
                    write_on_edge(a, b, scratch.dist[a], scratch.dist[b], out);
                    return;
                }
            }
        }
        for (tri, tri_edges) in self.triangles.iter().zip(&self.triangle_edges) {
            let idx = tri.map(|i| i as usize);
            let unit = idx.map(|i| scratch.unit[i]);
            let dist = idx.map(|i| scratch.dist[i]);
            let mut cross = [DVec3::ZERO; 3];
            let mut k = [0.0; 3];
            let mut theta = [0.0; 3];
            for j in 0..3 {
                let (e, reversed) = tri_edges[j];
                let e = e as usize;
                let c = scratch.edge_cross[e];
                cross[j] = if reversed { -c } else { c };
                k[j] = scratch.edge_k[e];
                theta[j] = scratch.edge_theta[e];
            }
            match triangle_contribution(&unit, &dist, &cross, &k, &theta) {
                Contribution::Add(w) => {
                    for j in 0..3 {
                        out[idx[j]] += w[j];
                    }
                }
                Contribution::Skip => {}
                Contribution::OnTriangle => {
                    write_on_triangle(self.positions, idx, point, out);
                    return;
                }
            }
        }
        normalise(out);
    }
}

/// Cage coordinates Φ (`#points × #C`, Eq. 7) of `points` w.r.t. the rest cage: MVC of every
/// point, computed in parallel blocks of rows, several points at a time (SIMD across points; the
/// points near the cage surface go through [`MvcEvaluator::evaluate`]). `progress` (if any) is called from worker threads
/// with the number of points finished so far (every [`POINT_BLOCK`] points), in whatever order
/// the threads get there; the last call is `#points`, from the calling thread once every block
/// is done.
pub fn compute_cage_coords(
    cage: &TriMesh,
    points: &[DVec3],
    progress: Option<&(dyn Fn(usize) + Sync)>,
) -> Result<CageCoords, RigError> {
    super::check_coords_inputs(
        cage,
        points,
        "cage coordinates Φ (#V × #C)",
        cage.num_vertices(),
    )?;
    let evaluator = MvcEvaluator::new(&cage.positions, &cage.triangles);
    let (num_points, num_cage) = (points.len(), cage.num_vertices());
    // Φ is 8 · #V · #C bytes (62 MB at N = 3): not zero-filled first; the blocks below write every
    // entry, so the page faults of first touch are spread over the worker threads.
    let blocks_done = BlockProgress::new(progress, num_points);
    let first_non_finite = AtomicUsize::new(usize::MAX);
    // SAFETY: `evaluate_rows` writes all rows × columns of its block.
    let [matrix] = unsafe {
        fill_by_row_blocks(
            num_points,
            [num_cage],
            POINT_BLOCK,
            || BatchScratch::new(&evaluator),
            |scratch, start, [rows]| {
                let count = rows.nrows();
                if let Some(row) =
                    evaluate_rows(&evaluator, &points[start..start + count], scratch, rows)
                {
                    first_non_finite.fetch_min(start + row, Ordering::Relaxed);
                }
                blocks_done.block_done(count);
            },
        )
    };
    blocks_done.finish();
    match first_non_finite.into_inner() {
        usize::MAX => Ok(CageCoords::from_checked_matrix(matrix)),
        index => Err(RigError::NonFinite {
            what: "cage coordinate row",
            index,
        }),
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use proptest::prelude::*;

    /// Octahedron with outward CCW triangles; vertex k at `radii[k]` along ±axes.
    /// The triangles of [`octahedron`] (outward), shared by other tests' octahedra.
    pub(crate) const OCTAHEDRON_TRIANGLES: [[u32; 3]; 8] = [
        [0, 2, 4],
        [2, 1, 4],
        [1, 3, 4],
        [3, 0, 4],
        [2, 0, 5],
        [1, 2, 5],
        [3, 1, 5],
        [0, 3, 5],
    ];

    pub(crate) fn octahedron(radii: [f64; 6]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let dirs = [
            DVec3::X,
            DVec3::NEG_X,
            DVec3::Y,
            DVec3::NEG_Y,
            DVec3::Z,
            DVec3::NEG_Z,
        ];
        let positions = dirs.iter().zip(radii).map(|(d, r)| *d * r).collect();
        (positions, OCTAHEDRON_TRIANGLES.to_vec())
    }

    /// Icosphere (subdivided icosahedron, 42 vertices, 80 triangles) with per-vertex radii.
    pub(crate) fn icosphere(radii: &[f64]) -> (Vec<DVec3>, Vec<[u32; 3]>) {
        let t = (1.0 + 5f64.sqrt()) / 2.0;
        let mut pos: Vec<DVec3> = [
            (-1.0, t, 0.0),
            (1.0, t, 0.0),
            (-1.0, -t, 0.0),
            (1.0, -t, 0.0),
            (0.0, -1.0, t),
            (0.0, 1.0, t),
            (0.0, -1.0, -t),
            (0.0, 1.0, -t),
            (t, 0.0, -1.0),
            (t, 0.0, 1.0),
            (-t, 0.0, -1.0),
            (-t, 0.0, 1.0),
        ]
        .iter()
        .map(|&(x, y, z)| DVec3::new(x, y, z).normalize())
        .collect();
        let faces: [[u32; 3]; 20] = [
            [0, 11, 5],
            [0, 5, 1],
            [0, 1, 7],
            [0, 7, 10],
            [0, 10, 11],
            [1, 5, 9],
            [5, 11, 4],
            [11, 10, 2],
            [10, 7, 6],
            [7, 1, 8],
            [3, 9, 4],
            [3, 4, 2],
            [3, 2, 6],
            [3, 6, 8],
            [3, 8, 9],
            [4, 9, 5],
            [2, 4, 11],
            [6, 2, 10],
            [8, 6, 7],
            [9, 8, 1],
        ];
        let mut mid = std::collections::HashMap::new();
        let mut tris = Vec::new();
        let mut midpoint = |a: u32, b: u32, pos: &mut Vec<DVec3>| -> u32 {
            *mid.entry((a.min(b), a.max(b))).or_insert_with(|| {
                pos.push(((pos[a as usize] + pos[b as usize]) / 2.0).normalize());
                (pos.len() - 1) as u32
            })
        };
        for [a, b, c] in faces {
            let ab = midpoint(a, b, &mut pos);
            let bc = midpoint(b, c, &mut pos);
            let ca = midpoint(c, a, &mut pos);
            tris.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        for (p, r) in pos.iter_mut().zip(radii.iter().cycle()) {
            *p *= *r;
        }
        (pos, tris)
    }

    fn reproduction_error(pos: &[DVec3], w: &[f64], x: DVec3) -> f64 {
        let y: DVec3 = pos.iter().zip(w).map(|(p, &w)| *p * w).sum();
        y.distance(x)
    }

    fn both(pos: &[DVec3], tris: &[[u32; 3]], x: DVec3) -> (Vec<f64>, Vec<f64>) {
        let mut a = vec![0.0; pos.len()];
        mean_value_coordinates(pos, tris, x, &mut a);
        let ev = MvcEvaluator::new(pos, tris);
        let mut s = ev.scratch();
        let mut b = vec![0.0; pos.len()];
        ev.evaluate(x, &mut s, &mut b);
        (a, b)
    }

    #[test]
    fn at_vertex_gives_unit_weight() {
        let (pos, tris) = octahedron([1.0, 2.0, 1.5, 1.0, 0.7, 1.2]);
        for k in 0..6 {
            let (a, b) = both(&pos, &tris, pos[k]);
            for w in [a, b] {
                for (i, &wi) in w.iter().enumerate() {
                    assert_eq!(wi, if i == k { 1.0 } else { 0.0 });
                }
            }
        }
    }

    #[test]
    fn on_edge_interpolates_linearly() {
        let (pos, tris) = octahedron([1.0, 2.0, 1.5, 1.0, 0.7, 1.2]);
        let x = 0.3 * pos[0] + 0.7 * pos[2];
        let (a, b) = both(&pos, &tris, x);
        for w in [a, b] {
            assert!(
                (w[0] - 0.3).abs() < 1e-12 && (w[2] - 0.7).abs() < 1e-12,
                "{w:?}"
            );
            assert!(
                w.iter()
                    .enumerate()
                    .all(|(i, v)| i == 0 || i == 2 || *v == 0.0)
            );
        }
    }

    #[test]
    fn on_face_is_barycentric() {
        let (pos, tris) = octahedron([1.0, 2.0, 1.5, 1.0, 0.7, 1.2]);
        let x = 0.2 * pos[1] + 0.3 * pos[3] + 0.5 * pos[4];
        let (a, b) = both(&pos, &tris, x);
        for w in [a, b] {
            assert!((w[1] - 0.2).abs() < 1e-12, "{w:?}");
            assert!((w[3] - 0.3).abs() < 1e-12);
            assert!((w[4] - 0.5).abs() < 1e-12);
        }
    }

    #[test]
    fn near_surface_and_outside_reproduce_position() {
        let radii: Vec<f64> = (0..42)
            .map(|i| 1.0 + 0.3 * ((i * 7 % 11) as f64 / 11.0))
            .collect();
        let (pos, tris) = icosphere(&radii);
        let face = tris[17].map(|i| pos[i as usize]);
        let normal = (face[1] - face[0]).cross(face[2] - face[0]).normalize();
        let on_face = 0.2 * face[0] + 0.5 * face[1] + 0.3 * face[2];
        let on_edge = 0.4 * face[0] + 0.6 * face[1];
        for base in [on_face, on_edge, face[2]] {
            for offset in [
                -1e-3, -1e-6, -1e-9, -1e-12, 1e-12, 1e-9, 1e-6, 1e-3, 0.5, 3.0,
            ] {
                let x = base + offset * normal;
                let (a, b) = both(&pos, &tris, x);
                for w in [&a, &b] {
                    let sum: f64 = w.iter().sum();
                    assert!((sum - 1.0).abs() < 1e-10, "offset {offset}: sum {sum}");
                    let err = reproduction_error(&pos, w, x);
                    assert!(err < 1e-8, "offset {offset}: reproduction error {err}");
                }
                for (u, v) in a.iter().zip(&b) {
                    assert!((u - v).abs() < 1e-8 * (1.0 + u.abs()));
                }
            }
        }
        // Far outside: still reproduces (MVC are defined outside a closed cage).
        let x = DVec3::new(5.0, -3.0, 2.0);
        let (a, _) = both(&pos, &tris, x);
        assert!(reproduction_error(&pos, &a, x) < 1e-9);
        assert!(a.iter().any(|w| *w < 0.0));
    }

    #[test]
    fn interior_weights_positive_for_convex_cage() {
        let (pos, tris) = icosphere(&[1.0]);
        let (a, _) = both(&pos, &tris, DVec3::new(0.1, -0.2, 0.3));
        assert!(a.iter().all(|w| *w > 0.0));
    }

    #[test]
    fn cage_coords_matches_pointwise() {
        let radii: Vec<f64> = (0..42).map(|i| 1.0 + 0.1 * (i % 5) as f64).collect();
        let (pos, tris) = icosphere(&radii);
        let cage = TriMesh::new(pos.clone(), tris.clone()).unwrap();
        let points: Vec<DVec3> = (0..1000)
            .map(|i| {
                let f = i as f64;
                DVec3::new((f * 0.37).sin(), (f * 0.73).cos(), (f * 0.11).sin()) * 0.8
            })
            .collect();
        let count = AtomicUsize::new(0);
        let report = |n: usize| {
            count.fetch_max(n, Ordering::Relaxed);
        };
        let phi = compute_cage_coords(&cage, &points, Some(&report)).unwrap();
        assert_eq!(count.load(Ordering::Relaxed), points.len());
        let mut w = vec![0.0; pos.len()];
        for (i, &x) in points.iter().enumerate() {
            mean_value_coordinates(&pos, &tris, x, &mut w);
            for (k, &wk) in w.iter().enumerate() {
                assert!((phi.get(i, k) - wk).abs() < 1e-12);
            }
        }
        assert!(phi.max_partition_error() < 1e-12);
    }

    #[test]
    fn cage_coords_batches_handle_special_points() {
        // Batched evaluation with vertex / edge / face / near-surface / outside points mixed in
        // with regular ones must agree with the robust per-point function.
        let radii: Vec<f64> = (0..42)
            .map(|i| 1.0 + 0.3 * ((i * 7 % 11) as f64 / 11.0))
            .collect();
        let (pos, tris) = icosphere(&radii);
        let cage = TriMesh::new(pos.clone(), tris.clone()).unwrap();
        let face = tris[17].map(|i| pos[i as usize]);
        let normal = (face[1] - face[0]).cross(face[2] - face[0]).normalize();
        let mut points = Vec::new();
        for i in 0..37 {
            let f = i as f64;
            points.push(DVec3::new((f * 0.37).sin(), (f * 0.73).cos(), (f * 0.11).sin()) * 0.6);
            match i % 6 {
                0 => points.push(pos[i % pos.len()]),
                1 => points.push(0.4 * face[0] + 0.6 * face[1]),
                2 => points.push(0.2 * face[0] + 0.5 * face[1] + 0.3 * face[2]),
                3 => points.push(face[2] + 1e-10 * normal),
                4 => points.push(DVec3::new(5.0, -3.0, 2.0) * (1.0 + f)),
                _ => points.push(0.3 * face[0] + 0.7 * face[2] - 1e-9 * normal),
            }
        }
        let phi = compute_cage_coords(&cage, &points, None).unwrap();
        let mut w = vec![0.0; pos.len()];
        let mut row = vec![0.0; pos.len()];
        for (i, &x) in points.iter().enumerate() {
            mean_value_coordinates(&pos, &tris, x, &mut w);
            phi.row_into(i, &mut row);
            let reproduction = reproduction_error(&pos, &row, x);
            assert!(
                reproduction < 1e-9 * (1.0 + x.length()),
                "point {i}: {reproduction}"
            );
            // Far outside, the weights cancel (|w| ≫ 1): compare relative to their size.
            let size = w.iter().map(|v| v.abs()).sum::<f64>();
            for (k, &wk) in w.iter().enumerate() {
                assert!(
                    (row[k] - wk).abs() < 1e-10 * size.powi(2),
                    "point {i} ({x}), column {k}: {} vs {wk}",
                    row[k]
                );
            }
        }
    }

    proptest! {
        #[test]
        fn partition_of_unity_and_linear_precision(
            radii in proptest::collection::vec(0.5f64..2.0, 42),
            dir in (-1.0f64..1.0, -1.0f64..1.0, -1.0f64..1.0),
            t in 0.0f64..0.999,
            scale in 0.01f64..100.0,
        ) {
            let (mut pos, tris) = icosphere(&radii);
            pos.iter_mut().for_each(|p| *p *= scale);
            let d = DVec3::new(dir.0, dir.1, dir.2);
            prop_assume!(d.length() > 1e-3);
            // The cage is star-shaped w.r.t. the origin; the ray hits it beyond 0.5·scale·t.
            let x = d.normalize() * (0.5 * scale * t);
            let (a, b) = both(&pos, &tris, x);
            for w in [&a, &b] {
                let sum: f64 = w.iter().sum();
                prop_assert!((sum - 1.0).abs() < 1e-10);
                prop_assert!(reproduction_error(&pos, w, x) < 1e-9 * scale);
            }
        }

        #[test]
        fn octahedron_interior(
            radii in (0.3f64..3.0, 0.3f64..3.0, 0.3f64..3.0, 0.3f64..3.0, 0.3f64..3.0, 0.3f64..3.0),
            bary in (0.0f64..1.0, 0.0f64..1.0, 0.0f64..1.0, 0.0f64..1.0),
        ) {
            let radii = [radii.0, radii.1, radii.2, radii.3, radii.4, radii.5];
            let (pos, tris) = octahedron(radii);
            // Convex combination of origin and one face: inside the (star-shaped) octahedron.
            let face = tris[(bary.3 * 7.99) as usize].map(|i| pos[i as usize]);
            let (b0, b1) = (bary.0, bary.1 * (1.0 - bary.0));
            let on_face = b0 * face[0] + b1 * face[1] + (1.0 - b0 - b1) * face[2];
            let x = on_face * bary.2;
            let (a, _) = both(&pos, &tris, x);
            let sum: f64 = a.iter().sum();
            prop_assert!((sum - 1.0).abs() < 1e-10);
            prop_assert!(reproduction_error(&pos, &a, x) < 1e-9 * 3.0);
        }
    }
}
