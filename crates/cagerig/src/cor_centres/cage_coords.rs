//! Cage coordinates of the centres of rotation, Λ = S·Φ (`#V × #C`, Eq. 14), computed without
//! forming S, so that the CoR centres follow rest-cage edits as CoRs = Λ·C.
//!
//! With the factored CoR matrix S = A·B of [`super::exact`] (A: vertex clusters × triangle
//! patches, similarity- and area-weighted; B: patches × vertices, the area-weighted mean of the
//! patch's triangle centroids), Λ = A·(B·Φ):
//!
//! `Λ_i = Σ_P s(ω_i, ω_P) α_P Φ_P / Σ_P s(ω_i, ω_P) α_P`, with `Φ_P = (B·Φ)_P` the area-weighted
//! mean of the patch's triangle coordinate rows `Φ_t = (Φ_a + Φ_b + Φ_c)/3` (a centroid is the mean
//! of its corners and M = ΦC, Eq. 7).
//!
//! S itself has O(#V) entries per row on fine meshes (every triangle of a joint pair's region
//! contributes), so S and S·Φ are infeasible beyond a few ten thousand vertices. B·Φ costs
//! O(#F·#C) and A·(B·Φ) O(nnz(A)·#C), where A has one row per vertex CLUSTER (vertices whose
//! quantised weight rows coincide, [`CorCentresMethod::Clustered`]) over triangle PATCHES
//! (triangles with coinciding quantised ω_t): both counts are bounded by the resolution of the
//! weight space, not of the mesh. Each row of A is evaluated and folded into Λ at once, so A is
//! never stored.
//!
//! Vertices without a centre (single influence, or zero total similarity) have S_ii = 1, i.e.
//! Λ_i = Φ_i. Rows of Λ are convex combinations of rows of Φ, so they sum to 1 when Φ's do.

use std::sync::atomic::{AtomicUsize, Ordering};

use faer::Mat;
use glam::DVec3;
use rayon::prelude::*;

use super::exact::{
    CorCentresFactored, CorCentresOptions, CorProblem, RowScratch, centre_row,
    check_cage_coord_rows,
};
use crate::SkinWeights;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::memory_estimate::zeroed_table;

#[cfg(doc)]
use super::exact::CorCentresMethod;

/// Λ = S·Φ (`#V × #C`, Eq. 14) for the rest mesh (`rest_positions` M: `#V`, `triangles`: `#F`),
/// skinning weights Ω (`#V × #J`) and cage coordinates Φ (`#V × #C`) of the same vertices; the CoR
/// centres are then Λ·C for the rest cage C. `options` as for
/// [`super::exact::compute_cor_centres_factored`] (use [`CorCentresMethod::Clustered`] on
/// large meshes).
///
/// `progress(done, total)` is called from worker threads as vertex clusters complete.
pub fn compute_cor_cage_coords(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    cage_coords: &CageCoords,
    options: &CorCentresOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CageCoords, RigError> {
    let num_vertices = rest_positions.len();
    check_cage_coord_rows(cage_coords, num_vertices)?;
    let num_cage = cage_coords.num_cage_vertices();
    let problem = CorProblem::new(rest_positions, triangles, weights, options)?;
    let num_patches = problem.num_patches();

    // Φ_P = (B·Φ)_P, row-major (#P × #C) for the per-cluster accumulation.
    let patch_coords_columns = problem.patches.points.compose_dense(cage_coords)?;
    let mut patch_coords = zeroed_table("CoR patch coordinates", num_patches, "patches", num_cage)?;
    patch_coords
        .par_chunks_mut(num_cage.max(1))
        .enumerate()
        .with_min_len(256)
        .for_each(|(p, row)| patch_coords_columns.row_into(p, row));
    drop(patch_coords_columns);

    // Λ rows of the clusters: Σ_P A_cP Φ_P (#clusters × #C, row-major).
    let num_clusters = problem.clusters.len();
    let mut cluster_coords = zeroed_table(
        "CoR cluster coordinates",
        num_clusters,
        "clusters",
        num_cage,
    )?;
    let mut has_centre = vec![false; num_clusters];
    let done = AtomicUsize::new(0);
    if num_cage > 0 {
        cluster_coords
            .par_chunks_mut(num_cage)
            .zip(has_centre.par_iter_mut())
            .zip(problem.clusters.par_iter())
            .with_min_len(16)
            .for_each_init(
                || RowScratch::new(num_patches),
                |scratch, ((out, has), (joints, cluster_weights))| {
                    if let Some(row) =
                        centre_row(joints, cluster_weights, &problem.patches, options, scratch)
                    {
                        for (p, a) in row {
                            let phi = &patch_coords[p as usize * num_cage..][..num_cage];
                            for (o, &x) in out.iter_mut().zip(phi) {
                                *o += a * x;
                            }
                        }
                        *has = true;
                    }
                    let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                    if finished.is_multiple_of(256) || finished == num_clusters {
                        progress(finished, num_clusters);
                    }
                },
            );
    }
    drop(patch_coords);

    // Λ_i = the cluster's row, or Φ_i for vertices without a centre (S_ii = 1).
    let vertex_cluster = &problem.vertex_cluster;
    crate::memory_estimate::check_dense_allocation(
        "CoR cage coordinates Λ (#V × #C)",
        num_vertices,
        num_cage,
    )?;
    let matrix = Mat::from_fn(num_vertices, num_cage, |i, k| {
        let c = vertex_cluster[i];
        if c != CorCentresFactored::NO_CENTRE && has_centre[c as usize] {
            cluster_coords[c as usize * num_cage + k]
        } else {
            cage_coords.get(i, k)
        }
    });
    CageCoords::from_matrix(matrix)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cor_centres::exact::{CorCentresMethod, compute_cor_centres};

    /// A strip of quads along x in the plane z = 0, weights blending joint 0 → 1 → 2 along x.
    fn strip(n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>, SkinWeights) {
        super::super::test_strip::strip(
            n,
            |x, y| DVec3::new(x, y, 0.0),
            |x, _| {
                let t = 2.0 * x;
                if t <= 1.0 {
                    vec![1.0 - t, t, 0.0]
                } else {
                    vec![0.0, 2.0 - t, t - 1.0]
                }
            },
        )
    }

    /// Coordinates of the strip's points w.r.t. a 4-point "cage" (bilinear in the unit square):
    /// rows are non-negative, sum to 1, and ΦC reproduces the points.
    fn bilinear(points: &[DVec3]) -> (CageCoords, Vec<DVec3>) {
        let rows: Vec<Vec<f64>> = points
            .iter()
            .map(|p| {
                vec![
                    (1.0 - p.x) * (1.0 - p.y),
                    p.x * (1.0 - p.y),
                    p.x * p.y,
                    (1.0 - p.x) * p.y,
                ]
            })
            .collect();
        let cage = vec![
            DVec3::new(0.0, 0.0, 0.0),
            DVec3::new(1.0, 0.0, 0.0),
            DVec3::new(1.0, 1.0, 0.0),
            DVec3::new(0.0, 1.0, 0.0),
        ];
        (CageCoords::from_rows(&rows, 4).unwrap(), cage)
    }

    #[test]
    fn matches_s_times_phi_and_partition_of_unity() {
        let (p, tris, w) = strip(24);
        let (phi, cage) = bilinear(&p);
        for method in [
            CorCentresMethod::Exact,
            CorCentresMethod::Clustered {
                vertex_step: 0.01,
                patch_step: 0.05,
                weight_floor: 0.0,
            },
        ] {
            let options = CorCentresOptions {
                method,
                ..Default::default()
            };
            let lambda =
                compute_cor_cage_coords(&p, &tris, &w, &phi, &options, &|_, _| {}).unwrap();
            let s = compute_cor_centres(&p, &tris, &w, &options, &|_, _| {}).unwrap();
            let expected = s.compose_dense(&phi).unwrap();
            for i in 0..p.len() {
                let mut sum = 0.0;
                for k in 0..4 {
                    let x = lambda.get(i, k);
                    assert!((x - expected.get(i, k)).abs() < 1e-13, "{method:?} {i} {k}");
                    sum += x;
                }
                assert!((sum - 1.0).abs() < 1e-12, "{i}: {sum}");
            }
            // Λ·C = S·M since ΦC = M.
            let mut centres = vec![DVec3::ZERO; p.len()];
            lambda.apply(&cage, &mut centres);
            let mut from_s = vec![DVec3::ZERO; p.len()];
            s.apply(&p, &mut from_s);
            assert!(crate::mesh::max_distance(&centres, &from_s) < 1e-13);
            // Single-influence ends keep Λ_i = Φ_i.
            for i in [0, 1, 24, 25, 48, 49] {
                for k in 0..4 {
                    assert_eq!(lambda.get(i, k), phi.get(i, k), "{i}");
                }
            }
        }
    }

    #[test]
    fn rejects_mismatched_phi() {
        let (p, tris, w) = strip(4);
        let (phi, _) = bilinear(&p[1..]);
        assert!(matches!(
            compute_cor_cage_coords(&p, &tris, &w, &phi, &Default::default(), &|_, _| {}),
            Err(RigError::SizeMismatch { .. })
        ));
    }
}
