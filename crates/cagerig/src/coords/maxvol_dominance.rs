//! The dominance check of MaxVol (see [`super::maxvol`]) on big Φ: which rows of Φ (`#V × #C`)
//! have a coefficient |B[i, j]| > [`SWAP_THRESHOLD`] in B = Φ Φ̃⁻¹, without storing B, and
//! skipping rows that bounds from the previous check settle.

use faer::Mat;
use rayon::prelude::*;

use super::maxvol_lu::{SWAP_THRESHOLD, SeqLu};
use crate::cage_coords::CageCoords;
use crate::error::RigError;

/// Rows per parallel task of the dominance check (Φ Φ̃⁻¹ computed block by block).
const CHECK_BLOCK: usize = 2048;

/// Upper bounds on max_j |B[i, j]| (`#V`) for the selection `rows`, from a previous
/// [`dominance_violations`] call.
pub(crate) struct DominanceBounds {
    rows: Vec<usize>,
    row_max: Vec<f64>,
}

/// Relative safety margin of the bounds in [`dominance_violations`] (rounding in B, M).
const BOUND_MARGIN: f64 = 1e-9;

/// Rows i of Φ with max_j |B[i, j]| > [`SWAP_THRESHOLD`], B = Φ Φ̃⁻¹ (`#V × #C`) computed in
/// parallel blocks without storing it; at most `max_count` of them (largest
/// first). Errors if the selected submatrix is singular.
///
/// `bounds` carries max_j |B[i, j]| from call to call. With the previous selection S and its
/// B_S, the new one is B' = B_S M with M = Φ̃_S Φ̃'⁻¹, so max_j |B'[i, j]| ≤ max_j |B_S[i, j]| ·
/// ‖M‖₁ (maximum absolute column sum). Rows whose bound stays below the threshold are not
/// recomputed; after a few swaps ‖M‖₁ is close to 1 and most rows are skipped.
pub(crate) fn dominance_violations(
    phi: &CageCoords,
    rows: &[usize],
    bounds: &mut Option<DominanceBounds>,
    max_count: usize,
) -> Result<Vec<usize>, RigError> {
    let selected = phi.select_rows(rows);
    let inverse = SeqLu::new(selected).inverse();
    if !inverse.col_iter().all(|c| c.iter().all(|v| v.is_finite())) {
        return Err(RigError::Singular {
            what: "MaxVol submatrix",
        });
    }
    let matrix = phi.matrix();
    let (num_rows, rank) = (matrix.nrows(), matrix.ncols());
    // Growth of the row maxima since the bounds were taken (∞: recompute every row).
    let (mut row_max, growth) = match bounds.take() {
        Some(previous) => {
            let change = phi.select_rows(&previous.rows) * &inverse;
            let norm = (0..rank)
                .map(|j| change.col(j).iter().map(|v| v.abs()).sum::<f64>())
                .fold(0.0f64, f64::max);
            (previous.row_max, norm * (1.0 + BOUND_MARGIN))
        }
        None => (vec![f64::INFINITY; num_rows], f64::INFINITY),
    };
    let mut violators: Vec<(f64, usize)> = row_max
        .par_chunks_mut(CHECK_BLOCK)
        .enumerate()
        .map_init(
            || (Mat::<f64>::new(), Vec::with_capacity(CHECK_BLOCK)),
            |(buffer, recompute), (block, row_max)| {
                let start = block * CHECK_BLOCK;
                let height = row_max.len();
                // Rows of the block whose bound does not settle them.
                recompute.clear();
                for (r, m) in row_max.iter_mut().enumerate() {
                    let bound = *m * growth;
                    if bound < SWAP_THRESHOLD {
                        *m = bound;
                    } else {
                        recompute.push(r);
                    }
                }
                if recompute.is_empty() {
                    return Vec::new();
                }
                // Few rows: gather them; many: multiply the whole block (a gather costs about as
                // much as the product).
                let gather = 4 * recompute.len() < height;
                let count = if gather { recompute.len() } else { height };
                if buffer.nrows() < count {
                    buffer.resize_with(count, rank, |_, _| 0.0);
                }
                let mut b = buffer.as_mut().subrows_mut(0, count);
                let gathered: Mat<f64>;
                let source = if gather {
                    gathered = Mat::from_fn(count, rank, |r, k| matrix[(start + recompute[r], k)]);
                    gathered.as_ref()
                } else {
                    matrix.as_ref().subrows(start, height)
                };
                faer::linalg::matmul::matmul(
                    b.as_mut(),
                    faer::Accum::Replace,
                    source,
                    inverse.as_ref(),
                    1.0,
                    faer::Par::Seq,
                );
                let mut exact = vec![0.0f64; count];
                for k in 0..rank {
                    let col = b.as_ref().col(k);
                    for (m, v) in exact.iter_mut().zip(col.iter()) {
                        let a = v.abs();
                        *m = if a > *m { a } else { *m };
                    }
                }
                if !gather {
                    // Keep the recomputed rows' values, in `recompute` order.
                    for (slot, &r) in recompute.iter().enumerate() {
                        exact[slot] = exact[r];
                    }
                    exact.truncate(recompute.len());
                }
                for (&r, &m) in recompute.iter().zip(&exact) {
                    row_max[r] = m;
                }
                recompute
                    .iter()
                    .zip(exact)
                    .filter(|(_, m)| *m > SWAP_THRESHOLD)
                    .map(|(&r, m)| (m, start + r))
                    .collect::<Vec<_>>()
            },
        )
        .flatten()
        .collect();
    *bounds = Some(DominanceBounds {
        rows: rows.to_vec(),
        row_max,
    });
    violators.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    violators.truncate(max_count);
    Ok(violators.into_iter().map(|(_, i)| i).collect())
}
