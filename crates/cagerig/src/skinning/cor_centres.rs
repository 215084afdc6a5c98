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
//! weight rows quantise to the same key (same joints, `ln ω` rounded to multiples of
//! `relative_step`) share
//! one row of S, computed for the mean weight row of the cluster. Error is measured against the
//! exact form in the tests (Arm: see `tests/cor_arm.rs`).

use std::collections::HashMap;
use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;
use rayon::prelude::*;

use crate::SkinWeights;
use crate::error::RigError;
use crate::sparse_rows::SparseRows;

/// How the rows of S are evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CorCentresMethod {
    /// One evaluation per vertex (O(#V × triangles sharing two joints), parallel).
    Exact,
    /// One evaluation per cluster of vertices with equal quantised weight rows.
    Clustered {
        /// Relative quantisation step of the weights: weights are binned by
        /// `round(ln(ω) / relative_step)`, so members of a cluster differ by about this
        /// relative amount per weight (e.g. 0.02). Relative (not absolute) bins matter: a small
        /// weight on a third joint steers the centre between joint-pair regions.
        relative_step: f64,
    },
}

/// Options of [`compute_cor_centres`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorCentresOptions {
    /// Width σ of the similarity kernel (Le & Hodgins: 0.1).
    pub sigma: f64,
    /// Relative similarity mass that may be dropped per vertex (error ≤ this × bbox diagonal).
    pub mass_tolerance: f64,
    pub method: CorCentresMethod,
}

impl Default for CorCentresOptions {
    fn default() -> Self {
        Self {
            sigma: 0.1,
            mass_tolerance: 1e-5,
            method: CorCentresMethod::Exact,
        }
    }
}

/// Le–Hodgins similarity `s(w_p, w_v)` of two sparse weight rows (ascending joints).
pub fn weight_similarity(
    joints_p: &[u32],
    weights_p: &[f64],
    joints_v: &[u32],
    weights_v: &[f64],
    inv_sigma_sq: f64,
) -> f64 {
    // Common support, at most min(len) entries; rows are short (≤ a few dozen).
    let mut common_p = [0.0f64; 32];
    let mut common_v = [0.0f64; 32];
    let mut n = 0;
    let (mut a, mut b) = (0, 0);
    while a < joints_p.len() && b < joints_v.len() {
        match joints_p[a].cmp(&joints_v[b]) {
            std::cmp::Ordering::Less => a += 1,
            std::cmp::Ordering::Greater => b += 1,
            std::cmp::Ordering::Equal => {
                if n < common_p.len() {
                    common_p[n] = weights_p[a];
                    common_v[n] = weights_v[b];
                    n += 1;
                }
                a += 1;
                b += 1;
            }
        }
    }
    let mut sum = 0.0;
    for j in 0..n {
        for k in j + 1..n {
            let cross = common_p[j] * common_v[k] - common_p[k] * common_v[j];
            sum += common_p[j]
                * common_p[k]
                * common_v[j]
                * common_v[k]
                * (-cross * cross * inv_sigma_sq).exp();
        }
    }
    2.0 * sum
}

/// Triangle data shared by all rows: areas, averaged weights (CSR) and the joint-pair index.
struct TriangleTable<'a> {
    triangles: &'a [[u32; 3]],
    areas: Vec<f64>,
    row_start: Vec<u32>,
    joints: Vec<u32>,
    weights: Vec<f64>,
    /// Triangles (positive area) whose averaged weights contain both joints of the pair.
    by_pair: HashMap<(u32, u32), Vec<u32>>,
}

impl<'a> TriangleTable<'a> {
    fn new(rest: &[DVec3], triangles: &'a [[u32; 3]], weights: &SkinWeights) -> Self {
        let mut areas = Vec::with_capacity(triangles.len());
        let mut row_start = Vec::with_capacity(triangles.len() + 1);
        row_start.push(0u32);
        let mut joints = Vec::new();
        let mut tri_weights = Vec::new();
        let mut by_pair: HashMap<(u32, u32), Vec<u32>> = HashMap::new();
        let mut merged: Vec<(u32, f64)> = Vec::new();
        for (t, &[a, b, c]) in triangles.iter().enumerate() {
            let (pa, pb, pc) = (rest[a as usize], rest[b as usize], rest[c as usize]);
            let area = 0.5 * (pb - pa).cross(pc - pa).length();
            areas.push(area);
            merged.clear();
            for corner in [a, b, c] {
                let (js, ws) = weights.row(corner as usize);
                merged.extend(js.iter().zip(ws).map(|(&j, &w)| (j, w / 3.0)));
            }
            merged.sort_by_key(|e| e.0);
            let start = joints.len();
            for &(j, w) in &merged {
                if joints.len() > start && joints.last() == Some(&j) {
                    if let Some(x) = tri_weights.last_mut() {
                        *x += w;
                    }
                } else {
                    joints.push(j);
                    tri_weights.push(w);
                }
            }
            row_start.push(joints.len() as u32);
            if area > 0.0 {
                let js = &joints[start..];
                for (x, &j) in js.iter().enumerate() {
                    for &k in &js[x + 1..] {
                        by_pair.entry((j, k)).or_default().push(t as u32);
                    }
                }
            }
        }
        Self {
            triangles,
            areas,
            row_start,
            joints,
            weights: tri_weights,
            by_pair,
        }
    }

    fn row(&self, t: usize) -> (&[u32], &[f64]) {
        let range = self.row_start[t] as usize..self.row_start[t + 1] as usize;
        (&self.joints[range.clone()], &self.weights[range])
    }
}

/// Per-thread buffers for one row evaluation.
struct RowScratch {
    /// `stamp[t] == generation` ⇔ triangle t already collected for this row.
    stamp: Vec<u32>,
    generation: u32,
    /// Dense accumulator over mesh vertices and the list of touched columns.
    accumulator: Vec<f64>,
    touched: Vec<u32>,
    contributions: Vec<(f64, u32)>,
}

impl RowScratch {
    fn new(num_vertices: usize, num_triangles: usize) -> Self {
        Self {
            stamp: vec![0; num_triangles],
            generation: 0,
            accumulator: vec![0.0; num_vertices],
            touched: Vec::new(),
            contributions: Vec::new(),
        }
    }
}

/// Row of S for weights `(joints, weights)`; `None` when the total similarity is zero.
fn centre_row(
    joints: &[u32],
    weights: &[f64],
    table: &TriangleTable,
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
            let Some(list) = table.by_pair.get(&(j, k)) else {
                continue;
            };
            for &t in list {
                if scratch.stamp[t as usize] == scratch.generation {
                    continue;
                }
                scratch.stamp[t as usize] = scratch.generation;
                let (tj, tw) = table.row(t as usize);
                let s = weight_similarity(joints, weights, tj, tw, inv_sigma_sq);
                let mass = s * table.areas[t as usize];
                if mass > 0.0 {
                    total += mass;
                    scratch.contributions.push((mass, t));
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
    let kept_total = total - dropped;
    let scale = 1.0 / (3.0 * kept_total);
    for &(mass, t) in &scratch.contributions[first_kept..] {
        for k in table.triangles[t as usize] {
            let acc = &mut scratch.accumulator[k as usize];
            if *acc == 0.0 {
                scratch.touched.push(k);
            }
            *acc += mass * scale;
        }
    }
    scratch.touched.sort_unstable();
    let row = scratch
        .touched
        .iter()
        .map(|&k| (k, std::mem::take(&mut scratch.accumulator[k as usize])))
        .collect();
    scratch.touched.clear();
    Some(row)
}

/// Computes the CoR matrix S (`#V × #V`, CoRs = S·M) of Eq. 5 for the rest mesh
/// (`rest_positions` M: `#V`, `triangles`: `#F`) and skinning weights Ω (`#V × #J`).
///
/// `progress(done, total)` is called from worker threads as rows (or clusters) complete.
pub fn compute_cor_centres(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    options: &CorCentresOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<SparseRows, RigError> {
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
    if !(options.sigma.is_finite() && options.sigma > 0.0) {
        return Err(RigError::Invalid(format!(
            "CoR similarity width sigma must be positive, got {}",
            options.sigma
        )));
    }
    let table = TriangleTable::new(rest_positions, triangles, weights);

    // Representatives: (joints, weights) evaluated once; every vertex maps to one or to None.
    let mut rep_joints: Vec<Vec<u32>> = Vec::new();
    let mut rep_weights: Vec<Vec<f64>> = Vec::new();
    let mut vertex_rep: Vec<Option<u32>> = vec![None; num_vertices];
    match options.method {
        CorCentresMethod::Exact => {
            for (v, rep) in vertex_rep.iter_mut().enumerate() {
                let (js, ws) = weights.row(v);
                if js.len() >= 2 {
                    *rep = Some(rep_joints.len() as u32);
                    rep_joints.push(js.to_vec());
                    rep_weights.push(ws.to_vec());
                }
            }
        }
        CorCentresMethod::Clustered { relative_step } => {
            if !(relative_step.is_finite() && relative_step > 0.0) {
                return Err(RigError::Invalid(format!(
                    "CoR clustering relative step must be positive, got {relative_step}"
                )));
            }
            let mut clusters: HashMap<Vec<(u32, i64)>, u32> = HashMap::new();
            let mut sums: Vec<HashMap<u32, f64>> = Vec::new();
            let mut counts: Vec<usize> = Vec::new();
            for (v, rep) in vertex_rep.iter_mut().enumerate() {
                let (js, ws) = weights.row(v);
                if js.len() < 2 {
                    continue;
                }
                let key: Vec<(u32, i64)> = js
                    .iter()
                    .zip(ws)
                    .map(|(&j, &w)| (j, (w.ln() / relative_step).round() as i64))
                    .collect();
                let id = *clusters.entry(key).or_insert_with(|| {
                    sums.push(HashMap::new());
                    counts.push(0);
                    (sums.len() - 1) as u32
                });
                for (&j, &w) in js.iter().zip(ws) {
                    *sums[id as usize].entry(j).or_insert(0.0) += w;
                }
                counts[id as usize] += 1;
                *rep = Some(id);
            }
            for (sum, count) in sums.into_iter().zip(counts) {
                let mut row: Vec<(u32, f64)> = sum.into_iter().collect();
                row.sort_by_key(|e| e.0);
                rep_joints.push(row.iter().map(|e| e.0).collect());
                rep_weights.push(row.iter().map(|e| e.1 / count as f64).collect());
            }
        }
    }

    let total = rep_joints.len();
    let done = AtomicUsize::new(0);
    let rows: Vec<Option<Vec<(u32, f64)>>> = (0..total)
        .into_par_iter()
        .with_min_len(16)
        .map_init(
            || RowScratch::new(num_vertices, triangles.len()),
            |scratch, r| {
                let row = centre_row(&rep_joints[r], &rep_weights[r], &table, options, scratch);
                let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                if finished.is_multiple_of(256) || finished == total {
                    progress(finished, total);
                }
                row
            },
        )
        .collect();

    let mut row_start = Vec::with_capacity(num_vertices + 1);
    row_start.push(0u32);
    let mut cols = Vec::new();
    let mut values = Vec::new();
    for (v, rep) in vertex_rep.iter().enumerate() {
        match rep.and_then(|r| rows[r as usize].as_ref()) {
            Some(row) => {
                cols.extend(row.iter().map(|e| e.0));
                values.extend(row.iter().map(|e| e.1));
            }
            None => {
                cols.push(v as u32);
                values.push(1.0);
            }
        }
        row_start.push(cols.len() as u32);
    }
    Ok(SparseRows {
        row_start,
        cols,
        values,
        ncols: num_vertices,
    })
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
        let mut p = Vec::new();
        let mut rows = Vec::new();
        for i in 0..=n {
            let x = i as f64 / n as f64;
            for y in [0.0, 1.0] {
                p.push(DVec3::new(x, y, 0.0));
                rows.push(vec![1.0 - x, x]);
            }
        }
        let mut tris = Vec::new();
        for i in 0..n as u32 {
            let (a, b, c, d) = (2 * i, 2 * i + 2, 2 * i + 3, 2 * i + 1);
            tris.push([a, b, c]);
            tris.push([a, c, d]);
        }
        (p, tris, SkinWeights::from_dense(&rows).unwrap().0)
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
                relative_step: 1e-9,
            },
            ..unpruned
        };
        let clustered = compute_cor_centres(&p, &tris, &w, &options, &|_, _| {}).unwrap();
        let mut c2 = vec![DVec3::ZERO; p.len()];
        clustered.apply(&p, &mut c2);
        assert!(crate::mesh::max_distance(&centres, &c2) < 1e-14);
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
