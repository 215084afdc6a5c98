//! Midpoint (1-to-4) subdivision of a rigged skin, carrying per-vertex sparse rows along.
//!
//! Each level splits every triangle `(a, b, c)` into `(a, ab, ca)`, `(ab, b, bc)`, `(ca, bc, c)`,
//! `(ab, bc, ca)`, where `ab` is the midpoint of edge `ab`, created once per undirected edge.
//! Existing vertices keep their index (`0..#V`); new vertices are appended in order of creation.
//! The geometry does not change (no smoothing), so the subdivided skin has the same shape.
//!
//! Per-vertex rows (skinning weights Ω, or any `#V × n` sparse matrix such as the CoR rows S with
//! `CoR_i = Σ_k S_ik M_k`) are extended with [`midpoint_rows`]: the row of a new vertex is the
//! average of its two parents' rows. Column indices are not touched, so rows that address the
//! ORIGINAL skin vertices keep addressing them: those vertices are still vertices of the
//! subdivided skin with the same index, so centres stay expressed in the original vertices.
//!
//! Counts per level (closed or open, manifold or not): `V' = V + E`, `F' = 4F`, `E' = 2E + 3F`;
//! the Euler characteristic is unchanged. The Arm (2089 v, 6244 e, 4156 f) gives 8333, 33 289 and
//! 133 073 vertices after 1, 2 and 3 levels.

use crate::skinning::DqBlendWeights;
use std::collections::HashMap;

use crate::error::RigError;
use crate::mesh::TriMesh;
use crate::skin_weights::{ROW_SUM_TOLERANCE, SkinWeights};

/// Result of [`subdivide_midpoint`].
#[derive(Debug, Clone, PartialEq)]
pub struct Subdivision {
    /// Subdivided skin: `#V' = #V + #new` vertices, `4^levels · #F` triangles.
    pub mesh: TriMesh,
    /// Skinning weights Ω' (`#V' × #J`): rows `0..#V` copied, new rows = mean of the parents' rows
    /// (rescaled to sum to 1 where one parent is unweighted; empty where both are).
    pub skin_weights: SkinWeights,
    /// For the new vertex `#V + k`, `edge_parents[k]` are the endpoints (ascending, indices into
    /// the subdivided mesh, always smaller than `#V + k`) of the edge it is the midpoint of.
    /// Apply [`midpoint_rows`] with it to carry any other per-vertex sparse rows along.
    pub edge_parents: Vec<[u32; 2]>,
}

/// `levels` levels of 1-to-4 midpoint subdivision of `mesh`, with Ω (`#V × #J`) carried along.
///
/// Errors: Ω has a different number of rows than the mesh has vertices, a triangle index is out
/// of range, or the result would not fit u32 indices.
pub fn subdivide_midpoint(
    mesh: &TriMesh,
    skin_weights: &SkinWeights,
    levels: usize,
) -> Result<Subdivision, RigError> {
    let num_vertices = mesh.num_vertices();
    if skin_weights.num_vertices() != num_vertices {
        return Err(RigError::SizeMismatch {
            what: "skinning weight rows vs. mesh vertices",
            expected: num_vertices,
            actual: skin_weights.num_vertices(),
        });
    }
    for &i in mesh.triangles.iter().flatten() {
        if i as usize >= num_vertices {
            return Err(RigError::IndexOutOfRange {
                what: "triangle vertex",
                index: i as usize,
                len: num_vertices,
            });
        }
    }
    let mut positions = mesh.positions.clone();
    let mut triangles = mesh.triangles.clone();
    let mut edge_parents: Vec<[u32; 2]> = Vec::new();
    for _ in 0..levels {
        // Upper bound on the new vertex count: E ≤ 3F.
        let bound = positions.len() as u64 + 3 * triangles.len() as u64;
        if bound > u32::MAX as u64 || 4 * triangles.len() as u64 > u32::MAX as u64 {
            return Err(RigError::Invalid(format!(
                "midpoint subdivision of a mesh with {} vertices and {} triangles would overflow u32 indices",
                positions.len(),
                triangles.len()
            )));
        }
        let mut midpoint_of: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 2);
        let mut refined = Vec::with_capacity(4 * triangles.len());
        for &[a, b, c] in &triangles {
            let mut midpoint = |p: u32, q: u32| -> u32 {
                let key = (p.min(q), p.max(q));
                *midpoint_of.entry(key).or_insert_with(|| {
                    let m = positions.len() as u32;
                    positions.push(0.5 * (positions[p as usize] + positions[q as usize]));
                    edge_parents.push([key.0, key.1]);
                    m
                })
            };
            let (ab, bc, ca) = (midpoint(a, b), midpoint(b, c), midpoint(c, a));
            refined.extend_from_slice(&[[a, ab, ca], [ab, b, bc], [ca, bc, c], [ab, bc, ca]]);
        }
        triangles = refined;
    }
    let (row_start, joints, weights) = skin_weights.csr();
    let (row_start, joints, mut weights) = midpoint_rows(row_start, joints, weights, &edge_parents);
    // Means of rows with ascending unique joints, positive weights and unit sums keep all three,
    // except where one parent is unweighted (empty row): rescale those rows to sum to 1.
    for v in num_vertices..row_start.len() - 1 {
        let row = &mut weights[row_start[v] as usize..row_start[v + 1] as usize];
        let sum: f64 = row.iter().sum();
        if !row.is_empty() && (sum - 1.0).abs() > ROW_SUM_TOLERANCE {
            row.iter_mut().for_each(|w| *w /= sum);
        }
    }
    let skin_weights =
        SkinWeights::from_csr_unchecked(skin_weights.num_joints(), row_start, joints, weights);
    Ok(Subdivision {
        mesh: TriMesh {
            positions,
            triangles,
        },
        skin_weights,
        edge_parents,
    })
}

/// Extends compressed sparse rows (`row_start` of length `#V + 1`, ascending `columns` per row,
/// `values`) by one row per entry of `edge_parents` (see [`Subdivision::edge_parents`]): the new
/// row is the entrywise mean of the two parents' rows (which may themselves be new rows created
/// earlier). Returns the extended `(row_start, columns, values)`; columns are left as they are.
///
/// Panics if a parent index is not smaller than the index of the row being created (never the case
/// for the parents produced by [`subdivide_midpoint`]).
pub fn midpoint_rows(
    row_start: &[u32],
    columns: &[u32],
    values: &[f64],
    edge_parents: &[[u32; 2]],
) -> (Vec<u32>, Vec<u32>, Vec<f64>) {
    let mut row_start = row_start.to_vec();
    let mut columns = columns.to_vec();
    let mut values = values.to_vec();
    let total_rows = row_start.len() - 1 + edge_parents.len();
    row_start.reserve(edge_parents.len());
    for &[p, q] in edge_parents {
        let row = |r: u32| row_start[r as usize] as usize..row_start[r as usize + 1] as usize;
        let (rp, rq) = (row(p), row(q));
        let (mut i, mut k) = (rp.start, rq.start);
        // Merge two ascending rows; a missing entry counts as zero.
        while i < rp.end || k < rq.end {
            let ci = if i < rp.end { columns[i] } else { u32::MAX };
            let ck = if k < rq.end { columns[k] } else { u32::MAX };
            let (column, value) = if ci == ck {
                i += 1;
                k += 1;
                (ci, 0.5 * (values[i - 1] + values[k - 1]))
            } else if ci < ck {
                i += 1;
                (ci, 0.5 * values[i - 1])
            } else {
                k += 1;
                (ck, 0.5 * values[k - 1])
            };
            columns.push(column);
            values.push(value);
        }
        row_start.push(columns.len() as u32);
    }
    debug_assert_eq!(row_start.len(), total_rows + 1);
    (row_start, columns, values)
}

#[cfg(test)]
mod tests {
    use glam::DVec3;

    use super::*;

    fn tetra() -> (TriMesh, SkinWeights) {
        let mesh = TriMesh::new(
            vec![DVec3::ZERO, DVec3::X, DVec3::Y, DVec3::Z],
            vec![[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]],
        )
        .unwrap();
        let (w, _) = SkinWeights::from_triplets(
            4,
            3,
            [
                (0, 0, 1.0),
                (1, 1, 1.0),
                (2, 2, 1.0),
                (3, 0, 0.5),
                (3, 2, 0.5),
            ],
        )
        .unwrap();
        (mesh, w)
    }

    fn euler(mesh: &TriMesh) -> i64 {
        let mut edges = std::collections::HashSet::new();
        for t in &mesh.triangles {
            for k in 0..3 {
                let (a, b) = (t[k], t[(k + 1) % 3]);
                edges.insert((a.min(b), a.max(b)));
            }
        }
        mesh.num_vertices() as i64 - edges.len() as i64 + mesh.num_triangles() as i64
    }

    #[test]
    fn one_level_of_a_tetrahedron() {
        let (mesh, w) = tetra();
        let s = subdivide_midpoint(&mesh, &w, 1).unwrap();
        assert_eq!(s.mesh.num_vertices(), 4 + 6);
        assert_eq!(s.mesh.num_triangles(), 16);
        assert_eq!(&s.mesh.positions[..4], &mesh.positions[..]);
        assert_eq!(euler(&s.mesh), 2);
        assert!((s.mesh.signed_volume() - mesh.signed_volume()).abs() < 1e-15);
        // The first new vertex is the midpoint of the first edge (0, 2).
        assert_eq!(s.edge_parents[0], [0, 2]);
        assert_eq!(s.mesh.positions[4], DVec3::new(0.0, 0.5, 0.0));
        assert_eq!(s.skin_weights.row(4).0, &[0, 2]);
        assert_eq!(s.skin_weights.row(4).1, &[0.5, 0.5]);
        // Midpoint of (2, 3): rows {2: 1} and {0: ½, 2: ½} → {0: ¼, 2: ¾}.
        let v = 4 + s.edge_parents.iter().position(|&e| e == [2, 3]).unwrap();
        assert_eq!(s.skin_weights.row(v).1, &[0.25, 0.75]);
        for v in 0..s.mesh.num_vertices() {
            let sum: f64 = s.skin_weights.row(v).1.iter().sum();
            assert!((sum - 1.0).abs() < 1e-15);
        }
        // Old rows unchanged.
        for v in 0..4 {
            assert_eq!(s.skin_weights.row(v), w.row(v));
        }
    }

    #[test]
    fn counts_follow_the_recurrence_and_orientation_is_kept() {
        let (mesh, w) = tetra();
        let zero = subdivide_midpoint(&mesh, &w, 0).unwrap();
        assert_eq!(zero.mesh, mesh);
        assert!(zero.edge_parents.is_empty());
        let (mut v, mut e, mut f) = (4usize, 6usize, 4usize);
        for levels in 1..=4 {
            (v, e, f) = (v + e, 2 * e + 3 * f, 4 * f);
            let s = subdivide_midpoint(&mesh, &w, levels).unwrap();
            assert_eq!(s.mesh.num_vertices(), v);
            assert_eq!(s.mesh.num_triangles(), f);
            assert_eq!(euler(&s.mesh), 2);
            assert!((s.mesh.signed_volume() - 1.0 / 6.0).abs() < 1e-14);
            // Every parent precedes its child; positions are midpoints.
            for (k, &[p, q]) in s.edge_parents.iter().enumerate() {
                let child = 4 + k;
                assert!(p < q && (q as usize) < child);
                let mid = 0.5 * (s.mesh.positions[p as usize] + s.mesh.positions[q as usize]);
                assert_eq!(s.mesh.positions[child], mid);
            }
        }
    }

    #[test]
    fn midpoint_rows_keep_original_columns() {
        // CoR-like rows over the 4 original vertices: CoR_i = Σ_k S_ik M_k, identity at rest.
        let (mesh, w) = tetra();
        let s = subdivide_midpoint(&mesh, &w, 2).unwrap();
        let row_start: Vec<u32> = (0..=4).collect();
        let columns: Vec<u32> = (0..4).collect();
        let values = vec![1.0; 4];
        let (rs, cols, vals) = midpoint_rows(&row_start, &columns, &values, &s.edge_parents);
        assert_eq!(rs.len(), s.mesh.num_vertices() + 1);
        assert!(cols.iter().all(|&c| c < 4));
        // With S = identity on the original vertices, S·M reproduces every subdivided position.
        for v in 0..s.mesh.num_vertices() {
            let range = rs[v] as usize..rs[v + 1] as usize;
            let p: DVec3 = cols[range.clone()]
                .iter()
                .zip(&vals[range.clone()])
                .map(|(&c, &x)| x * mesh.positions[c as usize])
                .sum();
            assert!(p.distance(s.mesh.positions[v]) < 1e-15, "vertex {v}");
            assert!(cols[range].windows(2).all(|w| w[0] < w[1]));
        }
    }

    #[test]
    fn midpoint_next_to_an_unweighted_vertex_is_renormalised() {
        let (mesh, _) = tetra();
        let (w, _) = SkinWeights::from_triplets(4, 2, [(0, 0, 1.0), (1, 1, 1.0)]).unwrap();
        let s = subdivide_midpoint(&mesh, &w, 1).unwrap();
        let row_of = |e: [u32; 2]| {
            let v = 4 + s.edge_parents.iter().position(|&x| x == e).unwrap();
            s.skin_weights.row(v)
        };
        assert_eq!(row_of([0, 1]), (&[0u32, 1][..], &[0.5, 0.5][..]));
        assert_eq!(row_of([0, 2]), (&[0u32][..], &[1.0][..]));
        assert!(row_of([2, 3]).0.is_empty());
    }

    #[test]
    fn mismatched_weights_are_rejected() {
        let (mesh, _) = tetra();
        let (w, _) = SkinWeights::from_triplets(3, 1, [(0, 0, 1.0)]).unwrap();
        assert!(matches!(
            subdivide_midpoint(&mesh, &w, 1),
            Err(RigError::SizeMismatch {
                expected: 4,
                actual: 3,
                ..
            })
        ));
        let (mesh, w) = tetra();
        let mut bad = mesh.clone();
        bad.triangles[0][1] = 9;
        assert!(matches!(
            subdivide_midpoint(&bad, &w, 1),
            Err(RigError::IndexOutOfRange { index: 9, .. })
        ));
    }
}

/// A subdivided rig: skin, Ω and (when given) the CoR rows, carried along by [`midpoint_rows`].
#[derive(Debug, Clone, PartialEq)]
pub struct SubdividedRig {
    /// The subdivided skin M (`#V'` vertices).
    pub mesh: TriMesh,
    /// Ω carried to the new vertices (`#V' × #J`).
    pub skin_weights: SkinWeights,
    /// CoR rows S (`#V' × #V`: new rows averaged, columns still address the original vertices).
    pub cor_rows: Option<crate::sparse_rows::SparseRows>,
    /// DQ blend weights b (`#V'`): a new vertex takes the mean of its edge's endpoints (in
    /// [0, 1] when they are).
    pub dq_blend_weights: Option<DqBlendWeights>,
}

/// [`subdivide_midpoint`] plus the CoR rows (`#V × #V`) and the DQ blend weights (`#V`) when the
/// rig has them.
pub fn subdivide_rig(
    mesh: &TriMesh,
    skin_weights: &SkinWeights,
    cor_rows: Option<&crate::sparse_rows::SparseRows>,
    dq_blend_weights: Option<&DqBlendWeights>,
    levels: usize,
) -> Result<SubdividedRig, RigError> {
    if let Some(b) = dq_blend_weights
        && b.len() != mesh.num_vertices()
    {
        return Err(RigError::SizeMismatch {
            what: "DQ blend weights vs. mesh vertices",
            expected: mesh.num_vertices(),
            actual: b.len(),
        });
    }
    if let Some(rows) = cor_rows
        && rows.nrows() != mesh.num_vertices()
    {
        return Err(RigError::SizeMismatch {
            what: "CoR rows vs. mesh vertices",
            expected: mesh.num_vertices(),
            actual: rows.nrows(),
        });
    }
    let sub = subdivide_midpoint(mesh, skin_weights, levels)?;
    let cor_rows = cor_rows.map(|rows| {
        let (row_start, cols, values) = rows.csr();
        let (row_start, cols, values) = midpoint_rows(row_start, cols, values, &sub.edge_parents);
        crate::sparse_rows::SparseRows::from_csr_unchecked(row_start, cols, values, rows.ncols())
    });
    let dq_blend_weights = dq_blend_weights
        .map(|b| {
            let mut values = b.values().to_vec();
            values.reserve(sub.edge_parents.len());
            for [a, c] in &sub.edge_parents {
                values.push(0.5 * (values[*a as usize] + values[*c as usize]));
            }
            DqBlendWeights::new(values)
        })
        .transpose()?;
    Ok(SubdividedRig {
        mesh: sub.mesh,
        skin_weights: sub.skin_weights,
        cor_rows,
        dq_blend_weights,
    })
}
