//! Green coordinates (Lipman, Levin & Cohen-Or, SIGGRAPH 2008) of points w.r.t. a closed
//! triangle cage: vertex coordinates φ (`#points × #C`) and face coordinates ψ
//! (`#points × #F`), with which every point inside the cage is
//!
//! `η = Σ_i φ_i(η) v_i + Σ_t ψ_t(η) n_t`        (rest cage, unit outward normals n_t)
//!
//! and follows a deformed cage as `η' = Σ_i φ_i v'_i + Σ_t ψ_t s_t n'_t` (see
//! [`super::stretched_normals`] for the stretch factors s_t). The per-triangle closed forms are in
//! [`super::green_triangle`].
//!
//! Orientation: Green coordinates need outward normals. A cage whose triangles wind the other
//! way (negative signed volume) is used with every triangle reversed; [`GreenCoords::triangles`]
//! holds the triangles as used, and every normal must be taken from them.

#![expect(
    unsafe_code,
    reason = "φ and ψ filled by disjoint row blocks without a zero fill (row_blocks)"
)]

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;

use super::green_batch::{GreenBatchPlan, GreenBatchScratch, evaluate_green_rows};
use super::green_triangle::GreenTriangle;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::row_blocks::{BlockProgress, fill_by_row_blocks};

/// Points per parallel task.
const POINT_BLOCK: usize = 256;

/// Green coordinates of a set of points (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub struct GreenCoords {
    /// φ, `#points × #C` (column-major, like MVC's Φ).
    pub vertex: CageCoords,
    /// ψ, `#points × #F`: one column per cage triangle, in the order of [`Self::triangles`].
    pub face: CageCoords,
    /// The cage triangles as used (outward-oriented), `#F`.
    pub triangles: Vec<[u32; 3]>,
}

/// The cage's triangles oriented outward: as given when the signed volume is positive, all
/// reversed otherwise.
pub fn outward_triangles(cage: &TriMesh) -> Vec<[u32; 3]> {
    let p = &cage.positions;
    let volume: f64 = cage
        .triangles
        .iter()
        .map(|t| p[t[0] as usize].dot(p[t[1] as usize].cross(p[t[2] as usize])) / 6.0)
        .sum();
    if volume >= 0.0 {
        cage.triangles.clone()
    } else {
        cage.triangles.iter().map(|t| [t[0], t[2], t[1]]).collect()
    }
}

/// Green coordinates of `points` w.r.t. the closed triangle cage `cage`, computed in parallel
/// blocks of points, [`LANES`](super::mvc_batch::LANES) points at a time (SIMD across points,
/// [`super::green_batch`]; the points on or within 1e-12 (relative) of a face's plane or a cage
/// vertex go through the per-point closed forms of [`super::green_triangle`]). `progress` (if any) is called from worker threads with the number of
/// points finished so far, in whatever order the threads get there; the last call is
/// `#points`, from the calling thread once every block is done.
///
/// Errors: an empty cage, a non-finite point, or coordinates too large to store.
pub fn compute_green_coords(
    cage: &TriMesh,
    points: &[DVec3],
    progress: Option<&(dyn Fn(usize) + Sync)>,
) -> Result<GreenCoords, RigError> {
    let num_cage = cage.num_vertices();
    super::check_coords_inputs(
        cage,
        points,
        "Green vertex and face coordinates (#V × (#C + #F))",
        num_cage + cage.triangles.len(),
    )?;
    let triangles = outward_triangles(cage);
    let num_faces = triangles.len();
    let frames: Vec<Option<GreenTriangle>> = triangles
        .iter()
        .map(|t| GreenTriangle::new(t.map(|v| cage.positions[v as usize])))
        .collect();
    let plan = GreenBatchPlan::new(&cage.positions, &triangles, &frames);
    let num_points = points.len();
    // φ and ψ are written straight into their column-major matrices by row blocks, without
    // zero-filling them first (every entry is written), so the page faults of first touch are
    // spread over the workers.
    let blocks_done = BlockProgress::new(progress, num_points);
    let first_non_finite = AtomicUsize::new(usize::MAX);
    // SAFETY: `evaluate_green_rows` writes all rows × columns of both blocks.
    let [vertex, face] = unsafe {
        fill_by_row_blocks(
            num_points,
            [num_cage, num_faces],
            POINT_BLOCK,
            || GreenBatchScratch::new(&plan),
            |scratch, start, [vertex_rows, face_rows]| {
                let count = vertex_rows.nrows();
                if let Some(row) = evaluate_green_rows(
                    &plan,
                    &points[start..start + count],
                    scratch,
                    vertex_rows,
                    face_rows,
                ) {
                    first_non_finite.fetch_min(start + row, Ordering::Relaxed);
                }
                blocks_done.block_done(count);
            },
        )
    };
    blocks_done.finish();
    match first_non_finite.into_inner() {
        usize::MAX => Ok(GreenCoords {
            vertex: CageCoords::from_checked_matrix(vertex),
            face: CageCoords::from_checked_matrix(face),
            triangles,
        }),
        index => Err(RigError::NonFinite {
            what: "Green coordinates of point",
            index,
        }),
    }
}

/// Unit normals of the cage triangles `triangles` at `positions` (`#F`); a degenerate triangle
/// gets the zero vector.
pub fn face_normals(positions: &[DVec3], triangles: &[[u32; 3]], out: &mut [DVec3]) {
    for (n, t) in out.iter_mut().zip(triangles) {
        let [a, b, c] = t.map(|v| positions[v as usize]);
        *n = (b - a).cross(c - a).normalize_or_zero();
    }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use crate::test_random::uniform;

    /// An octahedron-like closed cage around the origin (outward), slightly irregular.
    pub(crate) fn test_cage() -> TriMesh {
        let positions = vec![
            DVec3::new(1.1, 0.05, -0.02),
            DVec3::new(-0.9, 0.1, 0.03),
            DVec3::new(0.02, 1.2, 0.1),
            DVec3::new(-0.05, -1.0, 0.0),
            DVec3::new(0.1, -0.03, 1.05),
            DVec3::new(0.0, 0.08, -0.95),
        ];
        TriMesh {
            positions,
            triangles: crate::coords::mvc::tests::OCTAHEDRON_TRIANGLES.to_vec(),
        }
    }

    pub(crate) fn random_inside(seed: u64, count: usize) -> Vec<DVec3> {
        // The octahedron |x|+|y|+|z| < 0.8 lies inside the cage.
        let mut rng = uniform(seed);
        (0..count)
            .map(|_| {
                loop {
                    let p = DVec3::new(rng(), rng(), rng()) * 1.6 - 0.8;
                    if p.x.abs() + p.y.abs() + p.z.abs() < 0.8 {
                        break p;
                    }
                }
            })
            .collect()
    }

    fn reproduce(coords: &GreenCoords, cage: &[DVec3], normals: &[DVec3], i: usize) -> DVec3 {
        let mut p = DVec3::ZERO;
        for (k, c) in cage.iter().enumerate() {
            p += coords.vertex.get(i, k) * *c;
        }
        for (t, n) in normals.iter().enumerate() {
            p += coords.face.get(i, t) * *n;
        }
        p
    }

    #[test]
    fn reproduce_interior_points_and_sum_to_one() {
        let cage = test_cage();
        let points = random_inside(7, 200);
        let coords = compute_green_coords(&cage, &points, None).unwrap();
        let mut normals = vec![DVec3::ZERO; coords.triangles.len()];
        face_normals(&cage.positions, &coords.triangles, &mut normals);
        for (i, p) in points.iter().enumerate() {
            let sum: f64 = (0..cage.num_vertices())
                .map(|k| coords.vertex.get(i, k))
                .sum();
            assert!((sum - 1.0).abs() < 1e-13, "Σφ = {sum}");
            let q = reproduce(&coords, &cage.positions, &normals, i);
            assert!(p.distance(q) < 1e-13, "{p} vs {q}");
            for t in 0..coords.triangles.len() {
                assert!(coords.face.get(i, t) > 0.0);
            }
        }
    }

    #[test]
    fn inward_cage_is_used_reversed_with_the_same_result() {
        let cage = test_cage();
        let mut flipped = cage.clone();
        flipped.triangles.iter_mut().for_each(|t| t.swap(1, 2));
        let points = random_inside(3, 20);
        let a = compute_green_coords(&cage, &points, None).unwrap();
        let b = compute_green_coords(&flipped, &points, None).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn points_on_and_next_to_the_cage_are_reproduced() {
        let cage = test_cage();
        let p = &cage.positions;
        // A face centroid (on the cage), and points 1e-7 inside from an edge midpoint and from a
        // cage vertex. (Within d of an edge the solid angles vary on the scale d, and each face
        // rounds its own: the reproduction error grows to ~1e-10 at d = 1e-7, 1e-9 at 1e-9.)
        let centre = p.iter().copied().sum::<DVec3>() / p.len() as f64;
        let inside = |q: DVec3| q + (centre - q).normalize() * 1e-7;
        let points = vec![
            (p[0] + p[2] + p[4]) / 3.0,
            inside((p[0] + p[2]) / 2.0),
            inside(p[3]),
            inside((p[0] + p[2] + p[4]) / 3.0),
        ];
        let coords = compute_green_coords(&cage, &points, None).unwrap();
        let mut normals = vec![DVec3::ZERO; coords.triangles.len()];
        face_normals(&cage.positions, &coords.triangles, &mut normals);
        for (i, q) in points.iter().enumerate() {
            let r = reproduce(&coords, &cage.positions, &normals, i);
            assert!(q.distance(r) < 5e-10, "{q} vs {r}");
        }
    }

    #[test]
    fn rejects_empty_cage_and_non_finite_points() {
        let empty = TriMesh {
            positions: vec![DVec3::ZERO],
            triangles: vec![],
        };
        assert!(matches!(
            compute_green_coords(&empty, &[DVec3::ZERO], None),
            Err(RigError::EmptyCage)
        ));
        assert!(matches!(
            compute_green_coords(&test_cage(), &[DVec3::ZERO, DVec3::NAN], None),
            Err(RigError::NonFinite { index: 1, .. })
        ));
    }
}
