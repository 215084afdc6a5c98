//! Step 6 of the CoR grid ([`super::grid`]): the rows of Λ from the similarity tables G,
//! `Λ_i = Σ_pairs x y interp(G)(x, y) / its sum` (`x, y` the vertex's weights of the pair).
//!
//! The tables (`#slots × #C`, row-major) are far larger than the caches at fine meshes (11.6 MB
//! for the Arm at N = 4), and each (vertex, pair) reads 16 of their rows. A block of vertices is
//! therefore evaluated in the order of its (pair, x, y) — neighbouring weights share stencil
//! rows, which then come from L1/L2 — into a row-major block accumulator, and written to the
//! column-major Λ a column at a time. A vertex's pairs are summed in the order of their keys
//! (pair index first): deterministic, and equal to a per-vertex evaluation in pair-enumeration
//! order up to the last bits (the test below).

use super::grid_layout::{Grid, NONE, PairLookup, for_each_pair};
use crate::SkinWeights;
use crate::cage_coords::CageCoords;
use crate::row_blocks::RowBlock;
use crate::simd_dispatch::simd_dispatch;

/// The tables and how to find a (pair, node)'s row in them.
pub(super) struct Tables<'a> {
    pub grid: Grid,
    /// G, `#slots × #C` row-major.
    pub values: &'a [f64],
    /// Slot of (pair, node) at `pair · nodes_per_pair + node` ([`NONE`]: not tabulated).
    pub slot_of_node: &'a [u32],
    pub nodes_per_pair: usize,
    pub pair_of_key: &'a PairLookup<'a>,
    pub num_joints: usize,
    pub num_cage: usize,
}

/// Reused buffers of [`fill_rows`].
#[derive(Default)]
pub(super) struct RowScratch {
    /// (key, block row, x, y) of every (vertex, pair) of the block.
    items: Vec<(u64, u32, f64, f64)>,
    /// Block accumulator, `rows × #C` row-major.
    sums: Vec<f64>,
    /// Per block row: 1 / Σ of its row, or 0 when the row falls back to Φ.
    scale: Vec<f64>,
    /// One column of the block's rows of Λ.
    column: Vec<f64>,
}

/// Writes every entry of `out` (`rows × #C`, the rows of Λ from vertex `first`) from the
/// tables, falling back to Φ's row where a vertex has no tabulated pair (or a non-positive sum).
pub(super) fn fill_rows(
    out: &mut RowBlock,
    first: usize,
    weights: &SkinWeights,
    cage_coords: &CageCoords,
    tables: &Tables<'_>,
    scratch: &mut RowScratch,
) {
    let (rows, nc) = (out.nrows(), tables.num_cage);
    let RowScratch {
        items,
        sums,
        scale,
        column,
    } = scratch;
    items.clear();
    for r in 0..rows {
        let (js, ws) = weights.row(first + r);
        for_each_pair(ws, |a, b| {
            let key = js[a] as usize * tables.num_joints + js[b] as usize;
            let pair = tables.pair_of_key.get(key);
            if pair != NONE {
                let (x, y) = (ws[a], ws[b]);
                // Pair, then x and y quantised to 2⁻¹⁶: stencils of neighbouring keys overlap.
                let sort_key = (u64::from(pair) << 32)
                    | (((x * 65535.0) as u64) << 16)
                    | ((y * 65535.0) as u64);
                items.push((sort_key, r as u32, x, y));
            }
        });
    }
    items.sort_unstable_by_key(|item| (item.0, item.1));
    sums.clear();
    sums.resize(rows * nc, 0.0);
    accumulate(items, tables, sums);
    scale.clear();
    scale.extend(sums.chunks_exact(nc).map(|row| {
        let total: f64 = row.iter().sum();
        if total > 0.0 && total.is_finite() {
            1.0 / total
        } else {
            0.0
        }
    }));
    for c in 0..nc {
        let phi = &cage_coords.column(c)[first..first + rows];
        column.clear();
        column.extend((0..rows).map(|r| {
            if scale[r] != 0.0 {
                sums[r * nc + c] * scale[r]
            } else {
                phi[r]
            }
        }));
        out.write(0, c, column);
    }
}

simd_dispatch! {
    /// `sums[r] += x y interp(G_pair)(x, y)` for every item (sort key, block row r, x, y) in
    /// turn, vectorised for the CPU at hand (no fused multiply-add: the same bits on every CPU).
    fn accumulate(items: &[(u64, u32, f64, f64)], tables: &Tables<'_>, sums: &mut [f64])
        => accumulate_generic;
    avx512f: accumulate_avx512;
    avx2: accumulate_avx2;
}

/// Columns per register-held partial sum of [`accumulate_generic`].
const LANES: usize = 8;

#[inline(always)]
fn accumulate_generic(items: &[(u64, u32, f64, f64)], tables: &Tables<'_>, sums: &mut [f64]) {
    let nc = tables.num_cage;
    let mut stencil = [(0usize, 0.0f64); 16];
    for &(key, r, x, y) in items {
        let pair = (key >> 32) as usize;
        let n = tables.grid.stencil(x, y, &mut stencil);
        let slots = &tables.slot_of_node[pair * tables.nodes_per_pair..];
        for (node, w) in &mut stencil[..n] {
            *node = slots[*node] as usize * nc;
            *w *= x * y;
        }
        let stencil = &stencil[..n];
        let sum = &mut sums[r as usize * nc..][..nc];
        // The stencil's rows summed LANES columns at a time in registers, then added once.
        let mut chunks = sum.chunks_exact_mut(LANES);
        for (c, out) in (&mut chunks).enumerate() {
            let mut acc = [0.0f64; LANES];
            for &(start, w) in stencil {
                let row = &tables.values[start + c * LANES..][..LANES];
                for q in 0..LANES {
                    acc[q] += w * row[q];
                }
            }
            for q in 0..LANES {
                out[q] += acc[q];
            }
        }
        let done = nc - chunks.into_remainder().len();
        for c in done..nc {
            let acc: f64 = stencil
                .iter()
                .map(|&(start, w)| w * tables.values[start + c])
                .sum();
            sums[r as usize * nc + c] += acc;
        }
    }
}

#[cfg(test)]
#[expect(unsafe_code, reason = "the tests run every grid-row tier the CPU has")]
mod tests {
    use super::super::grid_layout::GridInterpolation;
    use super::*;

    /// Against the plain per-vertex evaluation (pairs in enumeration order, stencil nodes in
    /// order), on random tables, for both interpolations, with vertices of 1 to 3 joints and a
    /// pair that has no table (→ Φ's row).
    #[test]
    fn block_evaluation_matches_the_per_vertex_rule() {
        let mut random = crate::test_random::uniform(0x2545_f491_4f6c_dd1du64);
        // 11 cage columns: one register-width chunk of 8 and a tail of 3.
        let (num_joints, num_cage, rows) = (4usize, 11usize, 300usize);
        // Pairs (0,1), (0,2), (1,2) tabulated; (2,3) is not.
        let pair_keys: Vec<u32> = vec![1, 2, 6];
        let pair_of_key = PairLookup::new(&pair_keys, num_joints);
        for interpolation in [GridInterpolation::Bilinear, GridInterpolation::Bicubic] {
            let grid = Grid {
                step: 0.125,
                cells: 8,
                side: 11,
                interpolation,
            };
            let nodes_per_pair = grid.side * grid.side;
            let slot_of_node: Vec<u32> = (0..pair_keys.len() * nodes_per_pair)
                .map(|s| s as u32)
                .collect();
            let values: Vec<f64> = (0..slot_of_node.len() * num_cage)
                .map(|_| random())
                .collect();
            let mut triplets = Vec::new();
            for v in 0..rows {
                let joints: &[usize] = match v % 4 {
                    0 => &[0, 1],
                    1 => &[0, 1, 2],
                    2 => &[2, 3],
                    _ => &[1],
                };
                for &j in joints {
                    triplets.push((v, j, 0.05 + random()));
                }
            }
            let (weights, _) = SkinWeights::from_triplets(rows, num_joints, triplets).unwrap();
            let phi_rows: Vec<Vec<f64>> = (0..rows)
                .map(|_| (0..num_cage).map(|_| random()).collect())
                .collect();
            let cage_coords = CageCoords::from_rows(&phi_rows, num_cage).unwrap();
            let tables = Tables {
                grid,
                values: &values,
                slot_of_node: &slot_of_node,
                nodes_per_pair,
                pair_of_key: &pair_of_key,
                num_joints,
                num_cage,
            };
            // NaN-filled: every entry must be written.
            let mut out = faer::Mat::<f64>::from_fn(rows, num_cage, |_, _| f64::NAN);
            let col_stride = out.col_stride().unsigned_abs();
            // SAFETY: `out` holds `rows` rows of `num_cage` columns, `col_stride` apart, and is
            // not accessed otherwise while the block lives.
            let mut block = unsafe { RowBlock::new(out.as_ptr_mut(), col_stride, rows, num_cage) };
            fill_rows(
                &mut block,
                0,
                &weights,
                &cage_coords,
                &tables,
                &mut RowScratch::default(),
            );
            let mut stencil = [(0usize, 0.0f64); 16];
            for v in 0..rows {
                let (js, ws) = weights.row(v);
                let mut numerator = vec![0.0; num_cage];
                let mut any = false;
                for_each_pair(ws, |a, b| {
                    let pair = pair_of_key.get(js[a] as usize * num_joints + js[b] as usize);
                    if pair == NONE {
                        return;
                    }
                    any = true;
                    let (x, y) = (ws[a], ws[b]);
                    let n = grid.stencil(x, y, &mut stencil);
                    for &(node, w) in &stencil[..n] {
                        let slot = slot_of_node[pair as usize * nodes_per_pair + node] as usize;
                        for (o, &t) in numerator.iter_mut().zip(&values[slot * num_cage..]) {
                            *o += w * x * y * t;
                        }
                    }
                });
                let total: f64 = numerator.iter().sum();
                for c in 0..num_cage {
                    let expected = if any && total > 0.0 {
                        numerator[c] / total
                    } else {
                        phi_rows[v][c]
                    };
                    let got = out[(v, c)];
                    assert!(
                        (got - expected).abs() <= 1e-14 * expected.abs().max(1.0),
                        "{interpolation:?} vertex {v} column {c}: {got} vs {expected}"
                    );
                }
            }
        }
    }
}
