//! Centres of rotation p_i from Ω and the rest mesh M (Le & Hodgins 2016; Eq. 5), expressed as a
//! sparse linear combination of rest vertices so that they can follow the rest cage
//! (CoRs = S·M = (S·Φ)·C = Λ·C, Eq. 14).
//!
//! Discretisation over rest triangles t (area α_t, centroid v_t = (a+b+c)/3, weights
//! ω_t = (ω_a+ω_b+ω_c)/3):
//!
//! `p_i = Σ_t s(ω_i, ω_t) α_t v_t / Σ_t s(ω_i, ω_t) α_t`, hence
//! `S_ik = Σ_{t ∋ k} s(ω_i, ω_t) α_t / (3 Σ_t s(ω_i, ω_t) α_t)`,
//!
//! with the similarity `s(w_p, w_v) = Σ_{j≠k} w_pj w_pk w_vj w_vk exp(−(w_pj w_vk − w_pk w_vj)²/σ²)`
//! (σ = 0.1 in Le & Hodgins). Only joint pairs (j, k) influencing both sides contribute, so each
//! vertex visits only the triangles that share at least two joints with it (a joint-pair index).
//!
//! **Vertices without a centre.** s vanishes for every triangle when vertex i has a single
//! influence (no pair j≠k), and when it lies on no triangle of positive area. Its row is then
//! `S_ii = 1` (p_i = v_i): for a single influence the transform is rigid so any centre gives the
//! same result, and otherwise CoR skinning with p_i = v_i is exactly LBS for that vertex.
//!
//! **Pruning.** Per vertex, the smallest triangle contributions whose total is at most
//! `mass_tolerance` of Σ_t s α_t are dropped (and the rest renormalised). Since every centroid lies
//! in the mesh's bounding box, this moves p_i by at most `mass_tolerance × bbox diagonal`, and keeps
//! S sparse (the exp kernel makes most far-away contributions negligible).
//!
//! **Clustering** ([`CorCentresMethod::Clustered`]): p_i depends on ω_i only, so vertices whose
//! weight rows quantise to the same key (same joints, `ln(ω + floor)` rounded to multiples of
//! `vertex_step`) share
//! one row of S, computed for the mean weight row of the cluster. Error is measured against the
//! exact form in the tests (Arm: see `tests/cor_arm.rs`).

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::SkinWeights;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::sparse_rows::SparseRows;

pub use super::factored::CorCentresFactored;
pub use super::options::{CorCentresMethod, CorCentresOptions};
pub use super::similarity::weight_similarity;

/// Quantisation of weight rows: `(step, floor)`, see [`CorCentresMethod::Clustered`].
#[derive(Clone, Copy)]
struct Quantiser {
    step: f64,
    floor: f64,
}

impl Quantiser {
    /// Sparse weight rows keyed for clustering: same joints, `round(ln(ω + floor) / step)`.
    fn key(&self, joints: &[u32], weights: &[f64]) -> Vec<(u32, i64)> {
        joints
            .iter()
            .zip(weights)
            .map(|(&j, &w)| (j, ((w + self.floor).ln() / self.step).round() as i64))
            .collect()
    }
}

/// Accumulates weighted sparse rows per group and returns the weighted-mean rows (CSR parts).
#[derive(Default)]
struct GroupMeans {
    sums: Vec<HashMap<u32, f64>>,
    mass: Vec<f64>,
}

impl GroupMeans {
    fn add(&mut self, group: usize, joints: &[u32], weights: &[f64], mass: f64) {
        if group == self.sums.len() {
            self.sums.push(HashMap::new());
            self.mass.push(0.0);
        }
        for (&j, &w) in joints.iter().zip(weights) {
            *self.sums[group].entry(j).or_insert(0.0) += mass * w;
        }
        self.mass[group] += mass;
    }

    fn into_rows(self) -> Vec<(Vec<u32>, Vec<f64>)> {
        self.sums
            .into_iter()
            .zip(self.mass)
            .map(|(sum, mass)| {
                let mut row: Vec<(u32, f64)> = sum.into_iter().collect();
                row.sort_by_key(|e| e.0);
                (
                    row.iter().map(|e| e.0).collect(),
                    row.iter().map(|e| e.1 / mass).collect(),
                )
            })
            .collect()
    }
}

/// Patches (groups of positive-area triangles): area, mean weights, joint-pair index.
pub(crate) struct PatchTable {
    areas: Vec<f64>,
    weights: Vec<(Vec<u32>, Vec<f64>)>,
    /// Patches whose weights contain both joints of the pair.
    by_pair: HashMap<(u32, u32), Vec<u32>>,
    /// B: `#P × #V`.
    pub(crate) points: SparseRows,
}

impl PatchTable {
    fn new(
        rest: &[DVec3],
        triangles: &[[u32; 3]],
        weights: &SkinWeights,
        quantiser: Option<Quantiser>,
    ) -> Result<Self, RigError> {
        let mut keys: HashMap<Vec<(u32, i64)>, u32> = HashMap::new();
        let mut means = GroupMeans::default();
        let mut areas: Vec<f64> = Vec::new();
        let mut point_triplets: Vec<(usize, usize, f64)> = Vec::new();
        let mut merged: Vec<(u32, f64)> = Vec::new();
        let mut joints: Vec<u32> = Vec::new();
        let mut tri_weights: Vec<f64> = Vec::new();
        for &[a, b, c] in triangles {
            let (pa, pb, pc) = (rest[a as usize], rest[b as usize], rest[c as usize]);
            let area = 0.5 * (pb - pa).cross(pc - pa).length();
            if area.is_nan() || area <= 0.0 {
                continue;
            }
            // ω_t = (ω_a + ω_b + ω_c) / 3, sparse, ascending joints.
            merged.clear();
            for corner in [a, b, c] {
                let (js, ws) = weights.row(corner as usize);
                merged.extend(js.iter().zip(ws).map(|(&j, &w)| (j, w / 3.0)));
            }
            merged.sort_by_key(|e| e.0);
            joints.clear();
            tri_weights.clear();
            for &(j, w) in &merged {
                if joints.last() == Some(&j) {
                    if let Some(x) = tri_weights.last_mut() {
                        *x += w;
                    }
                } else {
                    joints.push(j);
                    tri_weights.push(w);
                }
            }
            let patch = match quantiser {
                None => areas.len(),
                Some(q) => {
                    let next = areas.len() as u32;
                    *keys.entry(q.key(&joints, &tri_weights)).or_insert(next) as usize
                }
            };
            if patch == areas.len() {
                areas.push(0.0);
            }
            areas[patch] += area;
            means.add(patch, &joints, &tri_weights, area);
            for corner in [a, b, c] {
                point_triplets.push((patch, corner as usize, area / 3.0));
            }
        }
        for t in point_triplets.iter_mut() {
            t.2 /= areas[t.0];
        }
        let points = SparseRows::from_triplets(areas.len(), rest.len(), point_triplets)?;
        let weights = means.into_rows();
        let mut by_pair: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        for (p, (js, _)) in weights.iter().enumerate() {
            for (x, &j) in js.iter().enumerate() {
                for &k in &js[x + 1..] {
                    by_pair.entry((j, k)).or_default().push(p as u32);
                }
            }
        }
        Ok(Self {
            areas,
            weights,
            by_pair,
            points,
        })
    }
}

/// Per-thread buffers for one row evaluation.
pub(crate) struct RowScratch {
    /// `stamp[p] == generation` ⇔ patch p already collected for this row.
    stamp: Vec<u32>,
    generation: u32,
    contributions: Vec<(f64, u32)>,
}

impl RowScratch {
    pub(crate) fn new(num_patches: usize) -> Self {
        Self {
            stamp: vec![0; num_patches],
            generation: 0,
            contributions: Vec::new(),
        }
    }
}

/// Row of A (patch, coefficient) for weights `(joints, weights)`; `None` when the total
/// similarity is zero. Coefficients are ascending in patch index and sum to 1.
pub(crate) fn centre_row(
    joints: &[u32],
    weights: &[f64],
    patches: &PatchTable,
    options: &CorCentresOptions,
    scratch: &mut RowScratch,
) -> Option<Vec<(u32, f64)>> {
    if joints.len() < 2 {
        return None;
    }
    let inv_sigma_sq = 1.0 / (options.sigma * options.sigma);
    scratch.generation = scratch.generation.wrapping_add(1);
    if scratch.generation == 0 {
        scratch.stamp.iter_mut().for_each(|s| *s = 0);
        scratch.generation = 1;
    }
    scratch.contributions.clear();
    let mut total = 0.0;
    for (x, &j) in joints.iter().enumerate() {
        for &k in &joints[x + 1..] {
            let Some(list) = patches.by_pair.get(&(j, k)) else {
                continue;
            };
            for &p in list {
                if scratch.stamp[p as usize] == scratch.generation {
                    continue;
                }
                scratch.stamp[p as usize] = scratch.generation;
                let (pj, pw) = &patches.weights[p as usize];
                let s = weight_similarity(joints, weights, pj, pw, inv_sigma_sq);
                let mass = s * patches.areas[p as usize];
                if mass > 0.0 {
                    total += mass;
                    scratch.contributions.push((mass, p));
                }
            }
        }
    }
    if !(total > 0.0 && total.is_finite()) {
        return None;
    }
    // Drop the smallest contributions totalling at most mass_tolerance · total.
    scratch
        .contributions
        .sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
    let budget = options.mass_tolerance.max(0.0) * total;
    let mut dropped = 0.0;
    let mut first_kept = 0;
    for &(mass, _) in &scratch.contributions {
        if dropped + mass > budget {
            break;
        }
        dropped += mass;
        first_kept += 1;
    }
    let scale = 1.0 / (total - dropped);
    let mut row: Vec<(u32, f64)> = scratch.contributions[first_kept..]
        .iter()
        .map(|&(mass, p)| (p, mass * scale))
        .collect();
    row.sort_unstable_by_key(|e| e.0);
    Some(row)
}

/// The checks shared by every computation of CoR centres (exact, clustered, Λ from clusters, Λ
/// from similarity tables): Ω has one row per rest vertex, the rest positions are finite,
/// triangles index existing vertices, and the similarity width σ is positive.
pub(crate) fn validate_cor_inputs(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    sigma: f64,
) -> Result<(), RigError> {
    let num_vertices = rest_positions.len();
    if weights.num_vertices() != num_vertices {
        return Err(RigError::SizeMismatch {
            what: "skinning weight rows vs rest vertices",
            expected: num_vertices,
            actual: weights.num_vertices(),
        });
    }
    if let Some(index) = rest_positions.iter().position(|p| !p.is_finite()) {
        return Err(RigError::NonFinite {
            what: "vertex",
            index,
        });
    }
    for tri in triangles {
        for &i in tri {
            if i as usize >= num_vertices {
                return Err(RigError::IndexOutOfRange {
                    what: "triangle vertex",
                    index: i as usize,
                    len: num_vertices,
                });
            }
        }
    }
    if !(sigma.is_finite() && sigma > 0.0) {
        return Err(RigError::Invalid(format!(
            "CoR similarity width sigma must be positive, got {sigma}"
        )));
    }
    Ok(())
}

/// The check of the Λ computations: Φ has one row per rest vertex.
pub(crate) fn check_cage_coord_rows(
    cage_coords: &CageCoords,
    num_vertices: usize,
) -> Result<(), RigError> {
    if cage_coords.num_vertices() != num_vertices {
        return Err(RigError::SizeMismatch {
            what: "cage coordinate rows vs rest vertices",
            expected: num_vertices,
            actual: cage_coords.num_vertices(),
        });
    }
    Ok(())
}

/// The inputs of the row evaluations: patches, vertex clusters and their mean weight rows.
pub(crate) struct CorProblem {
    pub(crate) patches: PatchTable,
    /// Per vertex: its cluster, or [`CorCentresFactored::NO_CENTRE`] (single influence).
    pub(crate) vertex_cluster: Vec<u32>,
    /// Mean weight row `(joints, weights)` per cluster.
    pub(crate) clusters: Vec<(Vec<u32>, Vec<f64>)>,
}

impl CorProblem {
    /// Validates the inputs, builds the patches (B) and the vertex clusters.
    pub(crate) fn new(
        rest_positions: &[DVec3],
        triangles: &[[u32; 3]],
        weights: &SkinWeights,
        options: &CorCentresOptions,
    ) -> Result<Self, RigError> {
        validate_cor_inputs(rest_positions, triangles, weights, options.sigma)?;
        let num_vertices = rest_positions.len();
        let (vertex_quantiser, patch_quantiser) = match options.method {
            CorCentresMethod::Exact => (None, None),
            CorCentresMethod::Clustered {
                vertex_step,
                patch_step,
                weight_floor,
            } => {
                let positive = |x: f64| x.is_finite() && x > 0.0;
                if !(positive(vertex_step) && positive(patch_step) && weight_floor >= 0.0) {
                    return Err(RigError::Invalid(format!(
                        "CoR clustering steps must be positive and the floor non-negative, got \
                         {vertex_step}, {patch_step}, {weight_floor}"
                    )));
                }
                (
                    Some(Quantiser {
                        step: vertex_step,
                        floor: weight_floor,
                    }),
                    Some(Quantiser {
                        step: patch_step,
                        floor: weight_floor,
                    }),
                )
            }
        };
        let patches = PatchTable::new(rest_positions, triangles, weights, patch_quantiser)?;

        // Vertex clusters (one per multi-influence vertex in exact mode).
        let mut keys: HashMap<Vec<(u32, i64)>, u32> = HashMap::new();
        let mut means = GroupMeans::default();
        let mut vertex_cluster = vec![CorCentresFactored::NO_CENTRE; num_vertices];
        for (v, cluster) in vertex_cluster.iter_mut().enumerate() {
            let (js, ws) = weights.row(v);
            if js.len() < 2 {
                continue;
            }
            let next = means.mass.len() as u32;
            let id = match vertex_quantiser {
                None => next,
                Some(q) => *keys.entry(q.key(js, ws)).or_insert(next),
            };
            means.add(id as usize, js, ws, 1.0);
            *cluster = id;
        }
        Ok(Self {
            patches,
            vertex_cluster,
            clusters: means.into_rows(),
        })
    }

    pub(crate) fn num_patches(&self) -> usize {
        self.patches.areas.len()
    }
}

/// Computes the CoR matrix of Eq. 5 in factored form `S = A·B` for the rest mesh
/// (`rest_positions` M: `#V`, `triangles`: `#F`) and skinning weights Ω (`#V × #J`).
///
/// `progress(done, total)` is called from worker threads as rows of A complete.
pub fn compute_cor_centres_factored(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    options: &CorCentresOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CorCentresFactored, RigError> {
    let problem = CorProblem::new(rest_positions, triangles, weights, options)?;
    let num_patches = problem.num_patches();
    let CorProblem {
        patches,
        mut vertex_cluster,
        clusters,
    } = problem;
    let total = clusters.len();
    let done = AtomicUsize::new(0);
    let rows: Vec<Option<Vec<(u32, f64)>>> = clusters
        .par_iter()
        .with_min_len(16)
        .map_init(
            || RowScratch::new(num_patches),
            |scratch, (js, ws)| {
                let row = centre_row(js, ws, &patches, options, scratch);
                let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                if finished.is_multiple_of(256) || finished == total {
                    progress(finished, total);
                }
                row
            },
        )
        .collect();

    // Clusters without a centre: their vertices use p_i = v_i; renumber the others.
    let mut renumber = vec![CorCentresFactored::NO_CENTRE; rows.len()];
    let mut row_start = vec![0u32];
    let mut cols = Vec::new();
    let mut values = Vec::new();
    for (c, row) in rows.iter().enumerate() {
        if let Some(row) = row {
            renumber[c] = (row_start.len() - 1) as u32;
            cols.extend(row.iter().map(|e| e.0));
            values.extend(row.iter().map(|e| e.1));
            row_start.push(cols.len() as u32);
        }
    }
    for c in vertex_cluster.iter_mut() {
        if *c != CorCentresFactored::NO_CENTRE {
            *c = renumber[*c as usize];
        }
    }
    Ok(CorCentresFactored {
        vertex_cluster,
        cluster_patch_weights: SparseRows::from_csr_unchecked(row_start, cols, values, num_patches),
        patch_points: patches.points,
    })
}

/// Computes the CoR matrix S (`#V × #V`, CoRs = S·M) of Eq. 5 for the rest mesh
/// (`rest_positions` M: `#V`, `triangles`: `#F`) and skinning weights Ω (`#V × #J`).
/// `S = A·B` multiplied out: fine for small meshes; use [`compute_cor_centres_factored`] for large
/// ones (see the module doc).
///
/// `progress(done, total)` is called from worker threads as rows complete.
pub fn compute_cor_centres(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    options: &CorCentresOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SparseRows, RigError> {
    compute_cor_centres_factored(rest_positions, triangles, weights, options, progress)
        .map(|factored| factored.to_sparse_rows())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn similarity_matches_definition() {
        // p = (0.5, 0.5), v = (0.2, 0.8): 2 · 0.25 · 0.16 · exp(−(0.4 − 0.1)²/0.01).
        let s = weight_similarity(&[0, 1], &[0.5, 0.5], &[0, 1], &[0.2, 0.8], 100.0);
        let expected = 2.0 * 0.25 * 0.16 * (-(0.3f64 * 0.3) * 100.0).exp();
        assert!((s - expected).abs() < 1e-17, "{s} vs {expected}");
        // Disjoint pair supports and single influences give zero.
        assert_eq!(
            weight_similarity(&[0, 1], &[0.5, 0.5], &[1, 2], &[0.5, 0.5], 100.0),
            0.0
        );
        assert_eq!(weight_similarity(&[3], &[1.0], &[3], &[1.0], 100.0), 0.0);
    }

    /// A strip of quads along x, weights blending joint 0 → joint 1 linearly in x.
    fn strip(n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>, SkinWeights) {
        super::super::test_strip::strip(n, |x, y| DVec3::new(x, y, 0.0), |x, _| vec![1.0 - x, x])
    }

    #[test]
    fn symmetric_strip_centres() {
        let (p, tris, w) = strip(20);
        let unpruned = CorCentresOptions {
            mass_tolerance: 0.0,
            ..Default::default()
        };
        let s = compute_cor_centres(&p, &tris, &w, &unpruned, &|_, _| {}).unwrap();
        let mut centres = vec![DVec3::ZERO; p.len()];
        s.apply(&p, &mut centres);
        // Pruning moves centres by at most mass_tolerance × bbox diagonal (here √2) and drops entries.
        let pruned =
            compute_cor_centres(&p, &tris, &w, &CorCentresOptions::default(), &|_, _| {}).unwrap();
        let mut pruned_centres = vec![DVec3::ZERO; p.len()];
        pruned.apply(&p, &mut pruned_centres);
        let moved = crate::mesh::max_distance(&centres, &pruned_centres);
        assert!(moved <= 1e-5 * 2f64.sqrt(), "{moved}");
        assert!(pruned.nnz() < s.nnz(), "{} vs {}", pruned.nnz(), s.nnz());
        // Single-influence ends: their own position.
        assert_eq!(centres[0], p[0]);
        assert_eq!(centres[41], p[41]);
        // Middle vertex (50/50): by symmetry the centre is at x = 0.5, y = 0.5.
        assert!(
            centres[20].abs_diff_eq(DVec3::new(0.5, 0.5, 0.0), 1e-12),
            "{}",
            centres[20]
        );
        // Rows are convex combinations.
        for i in 0..s.nrows() {
            let (_, vals) = s.row(i);
            assert!((vals.iter().sum::<f64>() - 1.0).abs() < 1e-12);
            assert!(vals.iter().all(|&x| x > 0.0));
        }
        // Centres of blended vertices lie near their own x (the weights vary along x).
        for i in (4..38).step_by(2) {
            assert!((centres[i].x - p[i].x).abs() < 0.1, "{i}: {}", centres[i]);
        }
        // Clustering with a fine step reproduces the exact rows (all weight rows are distinct).
        let options = CorCentresOptions {
            method: CorCentresMethod::Clustered {
                vertex_step: 1e-9,
                patch_step: 1e-9,
                weight_floor: 0.0,
            },
            ..unpruned
        };
        let clustered = compute_cor_centres(&p, &tris, &w, &options, &|_, _| {}).unwrap();
        let mut c2 = vec![DVec3::ZERO; p.len()];
        clustered.apply(&p, &mut c2);
        assert!(crate::mesh::max_distance(&centres, &c2) < 1e-14);
        // The factored form gives the same centres.
        let factored = compute_cor_centres_factored(&p, &tris, &w, &unpruned, &|_, _| {}).unwrap();
        let mut patch_scratch = vec![DVec3::ZERO; factored.num_patches()];
        let mut cluster_scratch = vec![DVec3::ZERO; factored.num_clusters()];
        factored.apply(&p, &mut patch_scratch, &mut cluster_scratch, &mut c2);
        assert!(crate::mesh::max_distance(&centres, &c2) < 1e-14);
        assert_eq!(factored.vertex_cluster[0], CorCentresFactored::NO_CENTRE);
    }

    #[test]
    fn rejects_bad_input() {
        let (p, tris, w) = strip(2);
        let bad = CorCentresOptions {
            sigma: 0.0,
            ..Default::default()
        };
        assert!(compute_cor_centres(&p, &tris, &w, &bad, &|_, _| {}).is_err());
        assert!(compute_cor_centres(&p[1..], &tris, &w, &Default::default(), &|_, _| {}).is_err());
    }
}
