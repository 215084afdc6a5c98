//! Cage coordinates of the centres of rotation, Λ (`#V × #C`, Eq. 5 and 14), from per-joint-pair
//! similarity tables on a grid over the weight simplex: O(#F + #pairs·nodes·bins·#C + #V·#C),
//! i.e. seconds where the clustered form of [`super::cage_coords`] takes minutes.
//!
//! Eq. 5 over rest triangles t (area α_t, weights ω_t = mean of the corner rows, coordinate row
//! Φ_t = mean of the corner rows of Φ, so that the centroid is v_t = Φ_t·C):
//!
//! `Λ_i = Σ_t s(ω_i, ω_t) α_t Φ_t / Σ_t s(ω_i, ω_t) α_t`,
//! `s(w_p, w_v) = Σ_{j≠k} w_pj w_pk w_vj w_vk exp(−(w_pj w_vk − w_pk w_vj)²/σ²)`.
//!
//! s is a sum over joint pairs (j, k), and the term of a pair depends on vertex i only through
//! (x, y) = (ω_ij, ω_ik):
//!
//! `Σ_t α_t s(ω_i, ω_t) Φ_t = 2 Σ_{j<k} x y G_jk(x, y)`,
//! `G_jk(x, y) = Σ_t α_t a_t b_t exp(−(x b_t − y a_t)²/σ²) Φ_t`, (a_t, b_t) = (ω_tj, ω_tk),
//!
//! where only triangles with a_t, b_t > 0 contribute. G_jk is smooth at the scale σ, so it is
//! tabulated on a regular grid (step `grid_step`, only the nodes that some vertex's interpolation
//! stencil touches) and interpolated (bicubic Catmull–Rom or bilinear). To build the tables, the
//! triangles of a pair are first aggregated into bins of (a_t, b_t) (`1/bin_resolution`), each
//! bin keeping Σ α a b, Σ α a b Φ_t and the α a b-weighted mean (ā, b̄), at which the kernel is
//! evaluated (so the binning error is second order in the bin size). A table is then a dense
//! product (nodes × bins)·(bins × #C).
//!
//! The denominator is the sum of the numerator's #C entries (rows of Φ sum to 1), so the rows of Λ
//! sum to 1 up to rounding whatever the interpolation error. Vertices without a centre (fewer
//! than two positive weights, no joint pair shared with any triangle, or a non-positive
//! interpolated total) keep Λ_i = Φ_i (S_ii = 1, as in [`super::exact`]).

#![expect(
    unsafe_code,
    reason = "Λ filled by disjoint row blocks without a zero fill (row_blocks)"
)]

use std::sync::atomic::{AtomicUsize, Ordering};

use glam::DVec3;

use super::exact::{check_cage_coord_rows, validate_cor_inputs};
use super::grid_bins::bin_triangles;
use super::grid_rows::{RowScratch, Tables, fill_rows};
use super::grid_tables::similarity_tables;
use crate::SkinWeights;
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::row_blocks::fill_by_row_blocks;

pub use super::grid_layout::GridInterpolation;
use super::grid_layout::{Grid, NONE, PairLookup, for_each_pair};

/// Options of [`compute_cor_cage_coords_grid`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CorGridOptions {
    /// Width σ of the similarity kernel (Le & Hodgins: 0.1).
    pub sigma: f64,
    /// Grid step h of the tables in weight space (in (0, 0.5]).
    pub grid_step: f64,
    /// Triangle weight pairs (a_t, b_t) are binned at `1 / bin_resolution` (≥ 1).
    pub bin_resolution: f64,
    /// How the tables are interpolated at a vertex.
    pub interpolation: GridInterpolation,
}

impl Default for CorGridOptions {
    /// σ = 0.1, h = 1/32, bins of 1/128, bicubic. Measured on the Arm (release, 2 shared cores):
    /// N = 0: max centre error 3.9e-4 (mean 2.7e-5) × bbox diagonal over all vertices; N = 3
    /// (133k vertices): 1.0e-4 (mean 1.1e-5) on 300 sampled vertices. Bins of 1/256: 1.1e-4 at
    /// N = 0 but about 3× slower at N = 3; bins of 1/64: about 2× faster at 8.3e-4. Binning
    /// dominates the error; the grid step barely matters down to h = 1/32 (h = 1/64: N = 0 max
    /// 3.9e-4, mean 2.7e-5; N = 3 max 1.0e-4, mean 1.0e-5, with 2.8× the table nodes and about
    /// twice the time; h = 1/16: N = 0 max 5.0e-4, mean 4.4e-5).
    fn default() -> Self {
        Self {
            sigma: 0.1,
            grid_step: 1.0 / 32.0,
            bin_resolution: 128.0,
            interpolation: GridInterpolation::Bicubic,
        }
    }
}

/// Vertices per rayon task in the evaluation.
const VERTEX_BLOCK: usize = 2048;
/// Λ (`#V × #C`, Eq. 14) for the rest mesh (`rest_positions` M: `#V`, `triangles`: `#F`),
/// skinning weights Ω (`#V × #J`) and cage coordinates Φ (`#V × #C`) of the same vertices: the
/// CoR centres (Eq. 5) are Λ·C for the rest cage C. See the module documentation for the method
/// and `options` for its accuracy.
///
/// `progress(done, total)` is called from worker threads as vertex blocks complete.
pub fn compute_cor_cage_coords_grid(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    cage_coords: &CageCoords,
    options: &CorGridOptions,
    progress: &(dyn Fn(usize, usize) + Sync),
) -> Result<CageCoords, RigError> {
    let num_vertices = rest_positions.len();
    validate(rest_positions, triangles, weights, cage_coords, options)?;
    let num_cage = cage_coords.num_cage_vertices();
    let num_joints = weights.num_joints();
    let cells = (1.0 / options.grid_step).ceil() as usize;
    let grid = Grid {
        step: options.grid_step,
        cells,
        side: cells + 3,
        interpolation: options.interpolation,
    };
    let nodes_per_pair = grid.side * grid.side;

    // 1–3. Triangles binned per joint pair, with each bin's Σ α a b Φ_t.
    let (pair_keys, binned) = bin_triangles(
        rest_positions,
        triangles,
        weights,
        cage_coords,
        options.bin_resolution,
    )?;
    let num_pairs = pair_keys.len();
    let pair_of_key = PairLookup::new(&pair_keys, num_joints);

    // 4. Nodes that some vertex's stencil touches, per pair → table slots.
    let mut slot_of_node = vec![NONE; num_pairs * nodes_per_pair];
    let mut stencil = [(0usize, 0.0f64); 16];
    for v in 0..num_vertices {
        let (js, ws) = weights.row(v);
        for_each_pair(ws, |a, b| {
            let pair = pair_of_key.get(js[a] as usize * num_joints + js[b] as usize);
            if pair != NONE {
                let n = grid.stencil(ws[a], ws[b], &mut stencil);
                for &(node, _) in &stencil[..n] {
                    slot_of_node[pair as usize * nodes_per_pair + node] = 0;
                }
            }
        });
    }
    let mut pair_nodes: Vec<Vec<u32>> = Vec::with_capacity(num_pairs);
    let mut num_slots = 0usize;
    for pair in 0..num_pairs {
        let slots = &mut slot_of_node[pair * nodes_per_pair..][..nodes_per_pair];
        let mut nodes = Vec::new();
        for (node, slot) in slots.iter_mut().enumerate() {
            if *slot != NONE {
                *slot = num_slots as u32;
                num_slots += 1;
                nodes.push(node as u32);
            }
        }
        pair_nodes.push(nodes);
    }

    // 5. Tables G (#slots × #C, row-major); the bins' #bins × #C coordinates go with them.
    let tables = similarity_tables(
        &grid,
        &pair_nodes,
        num_slots,
        binned,
        num_cage,
        options.sigma,
    )?;

    // 6. Λ_i = Σ_pairs x y interp(G)(x, y) / its sum, vertex blocks in parallel.
    crate::memory_estimate::check_dense_allocation(
        "CoR cage coordinates Λ (#V × #C)",
        num_vertices,
        num_cage,
    )?;
    let num_blocks = num_vertices.div_ceil(VERTEX_BLOCK);
    let done = AtomicUsize::new(0);
    let tables = Tables {
        grid,
        values: &tables,
        slot_of_node: &slot_of_node,
        nodes_per_pair,
        pair_of_key: &pair_of_key,
        num_joints,
        num_cage,
    };
    // Not zero-filled first. SAFETY: `fill_rows` writes every entry of its block (none when
    // num_cage = 0).
    let [matrix] = unsafe {
        fill_by_row_blocks(
            num_vertices,
            [num_cage],
            VERTEX_BLOCK,
            RowScratch::default,
            |scratch, first, [out]| {
                if num_cage > 0 {
                    fill_rows(out, first, weights, cage_coords, &tables, scratch);
                    let finished = done.fetch_add(1, Ordering::Relaxed) + 1;
                    progress(finished, num_blocks);
                }
            },
        )
    };
    CageCoords::from_matrix(matrix)
}

fn validate(
    rest_positions: &[DVec3],
    triangles: &[[u32; 3]],
    weights: &SkinWeights,
    cage_coords: &CageCoords,
    options: &CorGridOptions,
) -> Result<(), RigError> {
    validate_cor_inputs(rest_positions, triangles, weights, options.sigma)?;
    check_cage_coord_rows(cage_coords, rest_positions.len())?;
    if !(options.grid_step.is_finite() && options.grid_step > 0.0 && options.grid_step <= 0.5) {
        return Err(RigError::Invalid(format!(
            "CoR grid step must be in (0, 0.5], got {}",
            options.grid_step
        )));
    }
    if !(options.bin_resolution.is_finite() && (1.0..=65535.0).contains(&options.bin_resolution)) {
        return Err(RigError::Invalid(format!(
            "CoR bin resolution must be in [1, 65535], got {}",
            options.bin_resolution
        )));
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cor_centres::exact::weight_similarity;
    use crate::cor_centres::grid_layout::catmull_rom;

    #[test]
    fn pair_lookup_dense_and_sorted_agree() {
        let keys = [1u32, 5, 6, 15];
        let dense = PairLookup::new(&keys, 4);
        assert!(matches!(dense, PairLookup::Dense(_)));
        let sorted = PairLookup::Sorted(&keys);
        for key in 0..16 {
            let expected = keys
                .iter()
                .position(|&k| k as usize == key)
                .map_or(NONE, |p| p as u32);
            assert_eq!(dense.get(key), expected, "{key}");
            assert_eq!(sorted.get(key), expected, "{key}");
        }
        // Beyond the dense limit no #J² table is allocated.
        assert!(matches!(
            PairLookup::new(&keys, 65_536),
            PairLookup::Sorted(_)
        ));
        assert_eq!(PairLookup::new(&keys, 65_536).get(usize::MAX), NONE);
    }

    /// A strip of quads along x in the plane z = 0, weights blending joint 0 → 1 → 2 along x, with
    /// a bump of joint 2 near the middle so that three-joint rows occur.
    fn strip(n: usize) -> (Vec<DVec3>, Vec<[u32; 3]>, SkinWeights) {
        super::super::test_strip::strip(
            n,
            |x, y| DVec3::new(x, y, 0.1 * (3.0 * x).sin() * y),
            |x, y| {
                let t = 2.0 * x;
                let mut row = if t <= 1.0 {
                    vec![1.0 - t, t, 0.0]
                } else {
                    vec![0.0, 2.0 - t, t - 1.0]
                };
                if y > 0.0 && (0.3..0.5).contains(&x) {
                    row[2] += 0.2;
                    let s: f64 = row.iter().sum();
                    row.iter_mut().for_each(|w| *w /= s);
                }
                row
            },
        )
    }

    /// Coordinates w.r.t. a unit-cube "cage" (trilinear): rows non-negative, sum to 1, ΦC = p.
    fn trilinear(points: &[DVec3]) -> (CageCoords, Vec<DVec3>) {
        let mut cage = Vec::new();
        for c in 0..8 {
            cage.push(DVec3::new(
                (c & 1) as f64,
                (c >> 1 & 1) as f64,
                (c >> 2 & 1) as f64,
            ));
        }
        let rows: Vec<Vec<f64>> = points
            .iter()
            .map(|p| {
                cage.iter()
                    .map(|q| {
                        let f = |u: f64, v: f64| if v > 0.5 { u } else { 1.0 - u };
                        f(p.x, q.x) * f(p.y, q.y) * f((p.z + 0.5) / 1.0, q.z)
                    })
                    .collect()
            })
            .collect();
        let cage = cage
            .into_iter()
            .map(|q| DVec3::new(q.x, q.y, q.z - 0.5))
            .collect();
        (CageCoords::from_rows(&rows, 8).unwrap(), cage)
    }

    /// Exact Eq. 5 centre of vertex i.
    fn exact_centre(i: usize, p: &[DVec3], tris: &[[u32; 3]], w: &SkinWeights) -> DVec3 {
        let (js, ws) = w.row(i);
        let (mut num, mut den) = (DVec3::ZERO, 0.0);
        for &[a, b, c] in tris {
            let (pa, pb, pc) = (p[a as usize], p[b as usize], p[c as usize]);
            let area = 0.5 * (pb - pa).cross(pc - pa).length();
            let mut row = std::collections::BTreeMap::new();
            for v in [a, b, c] {
                let (tj, tw) = w.row(v as usize);
                for (&j, &x) in tj.iter().zip(tw) {
                    *row.entry(j).or_insert(0.0) += x / 3.0;
                }
            }
            let tj: Vec<u32> = row.keys().copied().collect();
            let tw: Vec<f64> = row.values().copied().collect();
            let s = weight_similarity(js, ws, &tj, &tw, 100.0) * area;
            num += s * (pa + pb + pc) / 3.0;
            den += s;
        }
        if den > 0.0 { num / den } else { p[i] }
    }

    #[test]
    fn matches_exact_centres_and_partition_of_unity() {
        let (p, tris, w) = strip(40);
        let (phi, cage) = trilinear(&p);
        for (interpolation, step, tolerance) in [
            (GridInterpolation::Bicubic, 1.0 / 64.0, 5e-5),
            (GridInterpolation::Bilinear, 1.0 / 128.0, 4e-4),
            // Fine grid and bins: close to exact.
            (GridInterpolation::Bicubic, 1.0 / 256.0, 1e-6),
        ] {
            let options = CorGridOptions {
                grid_step: step,
                bin_resolution: if step < 0.005 { 65535.0 } else { 256.0 },
                interpolation,
                ..Default::default()
            };
            let lambda =
                compute_cor_cage_coords_grid(&p, &tris, &w, &phi, &options, &|_, _| {}).unwrap();
            let mut centres = vec![DVec3::ZERO; p.len()];
            lambda.apply(&cage, &mut centres);
            let mut worst = 0.0f64;
            for (i, centre) in centres.iter().enumerate() {
                worst = worst.max(centre.distance(exact_centre(i, &p, &tris, &w)));
                let sum: f64 = (0..8).map(|k| lambda.get(i, k)).sum();
                assert!((sum - 1.0).abs() < 1e-12, "{i}: {sum}");
            }
            println!("{interpolation:?} h = {step}: max centre error {worst:.2e}");
            assert!(worst < tolerance, "{interpolation:?} {step}: {worst}");
            // Single-influence ends keep Λ_i = Φ_i.
            for i in [0, 1, 80, 81] {
                for k in 0..8 {
                    assert_eq!(lambda.get(i, k), phi.get(i, k), "{i}");
                }
            }
        }
    }

    #[test]
    fn catmull_rom_reproduces_quadratics() {
        for t in [0.0, 0.25, 0.6, 1.0] {
            let w = catmull_rom(t);
            assert!((w.iter().sum::<f64>() - 1.0).abs() < 1e-15);
            let f = |x: f64| 3.0 * x * x - x + 2.0;
            let v: f64 = (0..4).map(|n| w[n] * f(n as f64 - 1.0)).sum();
            assert!((v - f(t)).abs() < 1e-12, "{t}");
        }
    }

    #[test]
    fn rejects_bad_inputs() {
        let (p, tris, w) = strip(4);
        let (phi, _) = trilinear(&p);
        let (short_phi, _) = trilinear(&p[1..]);
        let run = |phi: &CageCoords, options: CorGridOptions| {
            compute_cor_cage_coords_grid(&p, &tris, &w, phi, &options, &|_, _| {})
        };
        assert!(matches!(
            run(&short_phi, Default::default()),
            Err(RigError::SizeMismatch { .. })
        ));
        for options in [
            CorGridOptions {
                sigma: 0.0,
                ..Default::default()
            },
            CorGridOptions {
                grid_step: 0.0,
                ..Default::default()
            },
            CorGridOptions {
                bin_resolution: 0.5,
                ..Default::default()
            },
        ] {
            assert!(matches!(run(&phi, options), Err(RigError::Invalid(_))));
        }
        assert!(run(&phi, Default::default()).is_ok());
    }
}
