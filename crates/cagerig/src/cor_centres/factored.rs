//! The CoR matrix S in factored form S = A·B (vertex clusters × patches × rest vertices), and
//! its application CoRs = S·M and product S (see [`super::exact`]).

use glam::DVec3;
use rayon::prelude::*;

use crate::sparse_rows::SparseRows;

/// The CoR matrix in factored form `S = A·B` (see the module doc).
#[derive(Debug, Clone, PartialEq)]
pub struct CorCentresFactored {
    /// Per vertex (`#V`): its row of `cluster_patch_weights`, or [`Self::NO_CENTRE`] (p_i = v_i).
    pub vertex_cluster: Vec<u32>,
    /// A: `#clusters × #P`, each row a convex combination of patches.
    pub cluster_patch_weights: SparseRows,
    /// B: `#P × #V`, each row a convex combination of rest vertices (a patch point).
    pub patch_points: SparseRows,
}

impl CorCentresFactored {
    /// Marks a vertex without a centre of rotation: p_i = v_i (CoR skinning = LBS there).
    pub const NO_CENTRE: u32 = u32::MAX;

    /// Number of mesh vertices `#V`.
    pub fn num_vertices(&self) -> usize {
        self.vertex_cluster.len()
    }

    /// Number of patches `#P` (rows of B).
    pub fn num_patches(&self) -> usize {
        self.patch_points.nrows()
    }

    /// Number of vertex clusters (rows of A).
    pub fn num_clusters(&self) -> usize {
        self.cluster_patch_weights.nrows()
    }

    /// CoRs = S·M = A·(B·M) (`rest_positions`, `out`: `#V`; `patch_scratch`: `#P`;
    /// `cluster_scratch`: `#clusters`). No allocation, parallel.
    ///
    /// # Panics
    /// If a slice length does not match.
    pub fn apply(
        &self,
        rest_positions: &[DVec3],
        patch_scratch: &mut [DVec3],
        cluster_scratch: &mut [DVec3],
        out: &mut [DVec3],
    ) {
        assert_eq!(out.len(), self.num_vertices(), "CoR centres: out");
        self.patch_points.apply(rest_positions, patch_scratch);
        self.cluster_patch_weights
            .apply(patch_scratch, cluster_scratch);
        out.par_iter_mut()
            .with_min_len(4096)
            .enumerate()
            .for_each(|(v, o)| {
                let c = self.vertex_cluster[v];
                *o = if c == Self::NO_CENTRE {
                    rest_positions[v]
                } else {
                    cluster_scratch[c as usize]
                };
            });
    }

    /// The product S = A·B (`#V × #V`). Rows of a cluster are duplicated; O(#V²) non-zeros on
    /// fine meshes, intended for small meshes and for forming Λ = S·Φ (Eq. 14).
    pub fn to_sparse_rows(&self) -> SparseRows {
        let num_vertices = self.num_vertices();
        let cluster_rows: Vec<Vec<(u32, f64)>> = (0..self.num_clusters())
            .into_par_iter()
            .map_init(
                || (vec![0.0f64; num_vertices], Vec::<u32>::new()),
                |(accumulator, touched), c| {
                    let (patches, coefficients) = self.cluster_patch_weights.row(c);
                    for (&p, &a) in patches.iter().zip(coefficients) {
                        let (vertices, b) = self.patch_points.row(p as usize);
                        for (&k, &bk) in vertices.iter().zip(b) {
                            let acc = &mut accumulator[k as usize];
                            if *acc == 0.0 {
                                touched.push(k);
                            }
                            *acc += a * bk;
                        }
                    }
                    touched.sort_unstable();
                    let row = touched
                        .iter()
                        .map(|&k| (k, std::mem::take(&mut accumulator[k as usize])))
                        .collect();
                    touched.clear();
                    row
                },
            )
            .collect();
        let mut row_start = Vec::with_capacity(num_vertices + 1);
        row_start.push(0u32);
        let mut cols = Vec::new();
        let mut values = Vec::new();
        for (v, &c) in self.vertex_cluster.iter().enumerate() {
            if c == Self::NO_CENTRE {
                cols.push(v as u32);
                values.push(1.0);
            } else {
                let row = &cluster_rows[c as usize];
                cols.extend(row.iter().map(|e| e.0));
                values.extend(row.iter().map(|e| e.1));
            }
            row_start.push(cols.len() as u32);
        }
        SparseRows::from_csr_unchecked(row_start, cols, values, num_vertices)
    }
}
