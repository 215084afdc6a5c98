//! MaxVol row selection (Goreinov, Oseledets, Savostyanov, Tyrtyshnikov et al. 2010; used by
//! Thiery et al. 2012 and by CageUp/CageRev): choose #C rows of the cage coordinates Φ
//! (`#V × #C`) whose square submatrix Φ̃ (`#C × #C`) has a (locally) maximal |det Φ̃|.
//!
//! 1. Initial rows: LU with partial (row) pivoting of Φ (greedy: each pivot is the row with the
//!    largest remaining entry in the next column), via faer.
//! 2. Refinement: B = Φ Φ̃⁻¹ (`#V × #C`, B restricted to the selected rows is the identity).
//!    While the largest |B[i, j]| exceeds [`SWAP_THRESHOLD`], replace selected row j by row i:
//!    |det Φ̃| grows by the factor |B[i, j]|, and B is updated in place by the rank-1 formula
//!    `B ← B − B[:, j] (B[i, :] − e_jᵀ) / B[i, j]` (one parallel pass fused with the next argmax).
//!
//! 3. Multi-start ([`MaxVolOptions`]): the swap refinement has many local maxima, so further
//!    starts (LU with shuffled column orders) run on a reduced candidate row set and the best
//!    result is refined once more on all rows.
//!
//! At convergence every row of Φ is a combination of the selected rows with coefficients of
//! magnitude ≤ [`SWAP_THRESHOLD`] (a "dominant" submatrix).

use faer::Mat;
use faer::linalg::solvers::DenseSolveCore;
use rayon::prelude::*;

use crate::cage_coords::CageCoords;
use crate::error::RigError;

/// Swap while some |B[i, j]| exceeds this (each swap multiplies |det| by at least this).
pub const SWAP_THRESHOLD: f64 = 1.0 + 1e-3;
/// Safety cap on swaps per cage vertex.
const MAX_SWAPS_PER_COLUMN: usize = 100;
/// B matrices with fewer entries are refined sequentially.
const PARALLEL_ENTRIES: usize = 1 << 20;
/// Rows per parallel task of the rank-1 update.
const ROW_BLOCK: usize = 8192;

/// Result of [`select_maxvol_rows`].
#[derive(Debug, Clone, PartialEq)]
pub struct MaxVolSelection {
    /// Selected mesh-vertex rows of Φ, `#C`, all distinct; `rows[j]` interpolates cage column j.
    pub rows: Vec<usize>,
    /// ln |det Φ̃| of the selected rows.
    pub log_abs_det: f64,
    /// Number of refinement swaps performed after the LU initialisation (of the winning start).
    pub swaps: usize,
}

/// Tuning of [`select_maxvol_rows_with`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct MaxVolOptions {
    /// Number of greedy starts (≥ 1). Start 0 uses the LU pivot rows of Φ; the others use LU
    /// with deterministically shuffled column orders on the candidate rows (see
    /// [`CANDIDATES_PER_COLUMN`]). The refinement
    /// has many local maxima (Arm: about ten distinct ones); several starts find better ones.
    pub starts: usize,
    /// Seed of the column shuffles.
    pub seed: u64,
}

impl Default for MaxVolOptions {
    fn default() -> Self {
        Self {
            starts: 16,
            seed: 0x5eed,
        }
    }
}

/// Candidate rows: per column k, the rows with the [`CANDIDATES_PER_COLUMN`] largest |Φ[i, k]|
/// (a row interpolating cage vertex k is one where Φ[:, k] dominates). All starts run on the
/// candidates only, which keeps them independent of #V.
pub const CANDIDATES_PER_COLUMN: usize = 32;

/// Rows per parallel task of the dominance check (Φ Φ̃⁻¹ computed block by block).
const CHECK_BLOCK: usize = 2048;

/// [`select_maxvol_rows_with`] with the default options.
pub fn select_maxvol_rows(phi: &CageCoords) -> Result<MaxVolSelection, RigError> {
    select_maxvol_rows_with(phi, &MaxVolOptions::default())
}

/// Selects #C rows of Φ (`#V × #C`) with locally maximal |det| (see module docs), the best of
/// `options.starts` greedy starts, made dominant on all rows of Φ.
///
/// The starts run on candidate rows (see [`CANDIDATES_PER_COLUMN`]); then one pass over Φ
/// computes B = Φ Φ̃⁻¹ block by block. Rows with some |B[i, j]| > [`SWAP_THRESHOLD`] (usually
/// none) join the candidates and the refinement continues from the current best, until no row
/// of Φ violates the bound. Errors if #V < #C or Φ is (numerically) rank deficient.
pub fn select_maxvol_rows_with(
    phi: &CageCoords,
    options: &MaxVolOptions,
) -> Result<MaxVolSelection, RigError> {
    let matrix = phi.matrix();
    let (num_rows, rank) = (matrix.nrows(), matrix.ncols());
    if rank == 0 {
        return Err(RigError::EmptyCage);
    }
    if num_rows < rank {
        return Err(RigError::SizeMismatch {
            what: "MaxVol needs at least #C mesh vertices",
            expected: rank,
            actual: num_rows,
        });
    }
    let scale = (0..rank)
        .map(|k| phi.column(k).iter().fold(0.0f64, |m, v| m.max(v.abs())))
        .fold(0.0, f64::max);
    let mut candidates = top_rows_per_column(phi, CANDIDATES_PER_COLUMN);
    let reduced = CageCoords::from_matrix(phi.select_rows(&candidates))?;
    // Start 0: LU pivots of the candidates (of all rows if the candidates are rank deficient).
    let first_rows = match lu_pivot_rows(reduced.matrix(), None, scale) {
        Ok(local) => local.iter().map(|&r| candidates[r]).collect(),
        Err(_) => {
            let rows = lu_pivot_rows(matrix, None, scale)?;
            candidates = merged(&candidates, &rows);
            rows
        }
    };
    // Round 1: all starts on the candidates; keep the best.
    let mut best: Option<MaxVolSelection> = None;
    let reduced = CageCoords::from_matrix(phi.select_rows(&candidates))?;
    let local_rows = |candidates: &[usize], rows: &[usize]| -> Vec<usize> {
        rows.iter()
            .filter_map(|r| candidates.binary_search(r).ok())
            .collect()
    };
    let mut state = options.seed;
    let initial_rows: Vec<Vec<usize>> = (0..options.starts.max(1))
        .filter_map(|start| {
            if start == 0 {
                return Some(local_rows(&candidates, &first_rows));
            }
            let mut order: Vec<usize> = (0..rank).collect();
            for i in (1..rank).rev() {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                order.swap(i, (state >> 33) as usize % (i + 1));
            }
            lu_pivot_rows(reduced.matrix(), Some(&order), scale).ok()
        })
        .collect();
    // The starts are independent: run them in parallel, keep the first best (deterministic).
    let outcomes: Vec<Option<MaxVolSelection>> = initial_rows
        .par_iter()
        .map(|initial| refine(&reduced, initial).ok().map(|(local, _)| local))
        .collect();
    for local in outcomes.into_iter().flatten() {
        if best
            .as_ref()
            .is_none_or(|b| local.log_abs_det > b.log_abs_det)
        {
            best = Some(MaxVolSelection {
                rows: local.rows.iter().map(|&r| candidates[r]).collect(),
                log_abs_det: local.log_abs_det,
                swaps: local.swaps,
            });
        }
    }
    let mut best = best.ok_or(RigError::Singular {
        what: "cage coordinates Φ (rank deficient: MaxVol needs rank #C)",
    })?;
    // Later rounds: add the rows of Φ that violate dominance, refine from the current best.
    loop {
        let violators = dominance_violations(phi, &best.rows)?;
        let before = candidates.len();
        candidates = merged(&candidates, &violators);
        if candidates.len() == before {
            // No violators (or, through rounding at the threshold, only rows the refinement
            // on the candidates already accepted).
            break;
        }
        let reduced = CageCoords::from_matrix(phi.select_rows(&candidates))?;
        let (local, _) = refine(&reduced, &local_rows(&candidates, &best.rows))?;
        best = MaxVolSelection {
            rows: local.rows.iter().map(|&r| candidates[r]).collect(),
            log_abs_det: local.log_abs_det,
            swaps: best.swaps + local.swaps,
        };
    }
    Ok(best)
}

/// Sorted union of two row lists (the first sorted and deduplicated).
fn merged(sorted: &[usize], extra: &[usize]) -> Vec<usize> {
    let mut rows: Vec<usize> = sorted.iter().chain(extra).copied().collect();
    rows.sort_unstable();
    rows.dedup();
    rows
}

/// Union over columns k of the `per_column` rows with the largest |Φ[i, k]|, sorted.
fn top_rows_per_column(phi: &CageCoords, per_column: usize) -> Vec<usize> {
    let rank = phi.num_cage_vertices();
    let mut rows: Vec<usize> = (0..rank)
        .into_par_iter()
        .flat_map_iter(|k| {
            let col = phi.column(k);
            let m = per_column.min(col.len());
            // Streaming top-m: `kept` holds (|value|, row); replace its minimum when beaten.
            let mut kept: Vec<(f64, usize)> = (0..m).map(|i| (col[i].abs(), i)).collect();
            let minimum = |kept: &[(f64, usize)]| {
                kept.iter()
                    .enumerate()
                    .fold(
                        (0, f64::INFINITY),
                        |a, (j, e)| if e.0 < a.1 { (j, e.0) } else { a },
                    )
            };
            let (mut slot, mut floor) = minimum(&kept);
            for (i, v) in col.iter().enumerate().skip(m) {
                if v.abs() > floor {
                    kept[slot] = (v.abs(), i);
                    (slot, floor) = minimum(&kept);
                }
            }
            kept.into_iter().map(|(_, i)| i)
        })
        .collect();
    rows.sort_unstable();
    rows.dedup();
    rows
}

/// Rows i of Φ with max_j |B[i, j]| > [`SWAP_THRESHOLD`], B = Φ Φ̃⁻¹ (`#V × #C`) computed in
/// parallel blocks without storing it; at most [`CANDIDATES_PER_COLUMN`]·#C of them (largest
/// first). Errors if the selected submatrix is singular.
fn dominance_violations(phi: &CageCoords, rows: &[usize]) -> Result<Vec<usize>, RigError> {
    let selected = phi.select_rows(rows);
    let lu = selected.partial_piv_lu();
    let inverse = lu.inverse();
    if !inverse.col_iter().all(|c| c.iter().all(|v| v.is_finite())) {
        return Err(RigError::Singular {
            what: "MaxVol submatrix",
        });
    }
    let matrix = phi.matrix();
    let (num_rows, rank) = (matrix.nrows(), matrix.ncols());
    let mut violators: Vec<(f64, usize)> = (0..num_rows.div_ceil(CHECK_BLOCK))
        .into_par_iter()
        .map_init(
            || Mat::<f64>::zeros(CHECK_BLOCK, rank),
            |buffer, block| {
                let start = block * CHECK_BLOCK;
                let height = CHECK_BLOCK.min(num_rows - start);
                let mut b = buffer.as_mut().subrows_mut(0, height);
                faer::linalg::matmul::matmul(
                    b.as_mut(),
                    faer::Accum::Replace,
                    matrix.as_ref().subrows(start, height),
                    inverse.as_ref(),
                    1.0,
                    faer::Par::Seq,
                );
                let mut row_max = vec![0.0f64; height];
                for k in 0..rank {
                    let col = b.as_ref().col(k);
                    for (m, v) in row_max.iter_mut().zip(col.iter()) {
                        *m = m.max(v.abs());
                    }
                }
                row_max
                    .into_iter()
                    .enumerate()
                    .filter(|(_, m)| *m > SWAP_THRESHOLD)
                    .map(|(i, m)| (m, start + i))
                    .collect::<Vec<_>>()
            },
        )
        .flatten()
        .collect();
    violators.sort_unstable_by(|a, b| b.0.total_cmp(&a.0));
    violators.truncate(CANDIDATES_PER_COLUMN * rank);
    Ok(violators.into_iter().map(|(_, i)| i).collect())
}

/// The first #C pivot rows of a row-pivoted LU of Φ (columns taken in `order` if given).
fn lu_pivot_rows(
    matrix: &Mat<f64>,
    order: Option<&[usize]>,
    scale: f64,
) -> Result<Vec<usize>, RigError> {
    let rank = matrix.ncols();
    let lu = match order {
        Some(order) => {
            Mat::from_fn(matrix.nrows(), rank, |i, k| matrix[(i, order[k])]).partial_piv_lu()
        }
        None => matrix.partial_piv_lu(),
    };
    let u = lu.U();
    for k in 0..rank {
        if u[(k, k)].abs().partial_cmp(&(1e-12 * scale)) != Some(std::cmp::Ordering::Greater) {
            return Err(RigError::Singular {
                what: "cage coordinates Φ (rank deficient: MaxVol needs rank #C)",
            });
        }
    }
    let (forward, _) = lu.P().arrays();
    Ok(forward[..rank].to_vec())
}

/// Runs the MaxVol swap refinement from the given `#C` distinct rows (see module docs).
/// Errors if the rows are out of range or their submatrix is singular.
pub fn refine_maxvol_rows(
    phi: &CageCoords,
    initial_rows: &[usize],
) -> Result<MaxVolSelection, RigError> {
    refine(phi, initial_rows).map(|(selection, _)| selection)
}

/// The refinement, also returning the final B = Φ Φ̃⁻¹ (`#V × #C`).
fn refine(
    phi: &CageCoords,
    initial_rows: &[usize],
) -> Result<(MaxVolSelection, Mat<f64>), RigError> {
    let initial_log_det = log_abs_det_of_rows(phi, initial_rows)?;
    if !initial_log_det.is_finite() {
        return Err(RigError::Singular {
            what: "initial MaxVol submatrix",
        });
    }
    let matrix = phi.matrix();
    let (num_rows, rank) = (matrix.nrows(), matrix.ncols());
    let mut rows = initial_rows.to_vec();
    // B = Φ Φ̃⁻¹.
    let selected = phi.select_rows(&rows);
    let inverse = selected.partial_piv_lu().inverse();
    // Small problems (the candidate rows) run sequentially: several starts run in parallel.
    let parallel = num_rows * rank >= PARALLEL_ENTRIES;
    let mut b = Mat::<f64>::zeros(num_rows, rank);
    faer::linalg::matmul::matmul(
        b.as_mut(),
        faer::Accum::Replace,
        matrix.as_ref(),
        inverse.as_ref(),
        1.0,
        if parallel {
            faer::get_global_parallelism()
        } else {
            faer::Par::Seq
        },
    );
    let mut pivot_column = vec![0.0; num_rows];
    let mut pivot_row = vec![0.0; rank];
    let mut swaps = 0;
    let mut best = if parallel {
        argmax_abs(&b)
    } else {
        rank_one_update_and_argmax_seq(&mut b, &vec![0.0; num_rows], &pivot_row_zero(rank))
    };
    while best.2 > SWAP_THRESHOLD && swaps < MAX_SWAPS_PER_COLUMN * rank {
        let (i, j, _) = best;
        let pivot = b[(i, j)];
        pivot_column.copy_from_slice(column(&b, j));
        for (k, r) in pivot_row.iter_mut().enumerate() {
            *r = (b[(i, k)] - if k == j { 1.0 } else { 0.0 }) / pivot;
        }
        rows[j] = i;
        swaps += 1;
        best = if parallel {
            rank_one_update_and_argmax(&mut b, &pivot_column, &pivot_row)
        } else {
            rank_one_update_and_argmax_seq(&mut b, &pivot_column, &pivot_row)
        };
    }
    let log_abs_det = log_abs_det_of_rows(phi, &rows)?;
    Ok((
        MaxVolSelection {
            rows,
            log_abs_det,
            swaps,
        },
        b,
    ))
}

/// ln |det Φ̃| of the `#C × #C` submatrix of the given rows (faer partial-pivot LU); −∞ when it is
/// exactly singular. Errors if `rows.len() != #C` or a row is out of range.
pub fn log_abs_det_of_rows(phi: &CageCoords, rows: &[usize]) -> Result<f64, RigError> {
    let rank = phi.num_cage_vertices();
    if rows.len() != rank {
        return Err(RigError::SizeMismatch {
            what: "MaxVol row count",
            expected: rank,
            actual: rows.len(),
        });
    }
    if let Some(&index) = rows.iter().find(|&&r| r >= phi.num_vertices()) {
        return Err(RigError::IndexOutOfRange {
            what: "MaxVol row",
            index,
            len: phi.num_vertices(),
        });
    }
    let lu = phi.select_rows(rows).partial_piv_lu();
    let u = lu.U();
    Ok((0..rank).map(|k| u[(k, k)].abs().ln()).sum())
}

/// Column k of a column-major owned matrix as a slice.
fn column(m: &Mat<f64>, k: usize) -> &[f64] {
    m.col(k)
        .try_as_col_major()
        .map(|c| c.as_slice())
        .unwrap_or(&[])
}

/// (row, column, |value|) of the entry with the largest magnitude.
fn argmax_abs(b: &Mat<f64>) -> (usize, usize, f64) {
    (0..b.ncols())
        .into_par_iter()
        .map(|k| {
            column(b, k)
                .iter()
                .enumerate()
                .fold((0, k, -1.0), |best, (i, v)| {
                    if v.abs() > best.2 {
                        (i, k, v.abs())
                    } else {
                        best
                    }
                })
        })
        .reduce(|| (0, 0, -1.0), max_entry)
}

fn max_entry(a: (usize, usize, f64), b: (usize, usize, f64)) -> (usize, usize, f64) {
    if b.2 > a.2 { b } else { a }
}

/// `B[:, k] -= pivot_column · pivot_row[k]` for every k, returning the new argmax |B|.
fn rank_one_update_and_argmax(
    b: &mut Mat<f64>,
    pivot_column: &[f64],
    pivot_row: &[f64],
) -> (usize, usize, f64) {
    b.par_row_chunks_mut(ROW_BLOCK)
        .enumerate()
        .map(|(block, mut chunk)| {
            let start = block * ROW_BLOCK;
            let height = chunk.nrows();
            let source = &pivot_column[start..start + height];
            let mut best = (0, 0, -1.0);
            for (k, &factor) in pivot_row.iter().enumerate() {
                let Some(col) = chunk.as_mut().col_mut(k).try_as_col_major_mut() else {
                    continue;
                };
                let col = col.as_slice_mut();
                let mut local = (0, -1.0f64);
                for (r, (v, s)) in col.iter_mut().zip(source).enumerate() {
                    *v -= s * factor;
                    if v.abs() > local.1 {
                        local = (r, v.abs());
                    }
                }
                if local.1 > best.2 {
                    best = (start + local.0, k, local.1);
                }
            }
            best
        })
        .reduce(|| (0, 0, -1.0), max_entry)
}

fn pivot_row_zero(rank: usize) -> Vec<f64> {
    vec![0.0; rank]
}

/// Sequential [`rank_one_update_and_argmax`] (a zero `pivot_row` just finds the argmax).
fn rank_one_update_and_argmax_seq(
    b: &mut Mat<f64>,
    pivot_column: &[f64],
    pivot_row: &[f64],
) -> (usize, usize, f64) {
    let mut best = (0, 0, -1.0);
    for (k, &factor) in pivot_row.iter().enumerate() {
        let Some(col) = b.as_mut().col_mut(k).try_as_col_major_mut() else {
            continue;
        };
        let mut local = (0, -1.0f64);
        for (r, (v, s)) in col.as_slice_mut().iter_mut().zip(pivot_column).enumerate() {
            *v -= s * factor;
            if v.abs() > local.1 {
                local = (r, v.abs());
            }
        }
        if local.1 > best.2 {
            best = (local.0, k, local.1);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;

    fn phi_from_fn(n: usize, r: usize, f: impl Fn(usize, usize) -> f64) -> CageCoords {
        CageCoords::from_matrix(Mat::from_fn(n, r, f)).unwrap()
    }

    /// Brute force over all subsets of size r.
    fn best_subset(phi: &CageCoords, n: usize, r: usize) -> f64 {
        fn rec(
            phi: &CageCoords,
            n: usize,
            r: usize,
            start: usize,
            cur: &mut Vec<usize>,
            best: &mut f64,
        ) {
            if cur.len() == r {
                *best = best.max(log_abs_det_of_rows(phi, cur).unwrap());
                return;
            }
            for i in start..n {
                cur.push(i);
                rec(phi, n, r, i + 1, cur, best);
                cur.pop();
            }
        }
        let mut best = f64::NEG_INFINITY;
        rec(phi, n, r, 0, &mut Vec::new(), &mut best);
        best
    }

    #[test]
    fn identity_rows_are_found() {
        // Rows 7, 3, 11 carry a scaled identity; all other rows are small combinations.
        let phi = phi_from_fn(15, 3, |i, k| match (i, k) {
            (7, 0) | (3, 1) | (11, 2) => 2.0,
            (7, _) | (3, _) | (11, _) => 0.0,
            _ => 0.1 * (((i * 3 + k * 5) % 7) as f64 - 3.0),
        });
        let sel = select_maxvol_rows(&phi).unwrap();
        let mut rows = sel.rows.clone();
        rows.sort();
        assert_eq!(rows, vec![3, 7, 11]);
        assert!((sel.log_abs_det - 3.0 * 2f64.ln()).abs() < 1e-12);
    }

    #[test]
    fn dominant_and_near_optimal_on_small_random() {
        for seed in 0..20u64 {
            let mut state = seed
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let mut rnd = || {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
            };
            let (n, r) = (10, 3);
            let values: Vec<f64> = (0..n * r).map(|_| rnd()).collect();
            let phi = phi_from_fn(n, r, |i, k| values[i * r + k]);
            let sel = select_maxvol_rows(&phi).unwrap();
            let best = best_subset(&phi, n, r);
            // A dominant submatrix has volume ≥ best / r^(r/2) (Goreinov et al.); usually equal.
            assert!(sel.log_abs_det >= best - 0.5 * (r as f64) * (r as f64).ln() - 1e-12);
            assert!(sel.log_abs_det <= best + 1e-12);
            let check = log_abs_det_of_rows(&phi, &sel.rows).unwrap();
            assert!((check - sel.log_abs_det).abs() < 1e-12);
            // Dominance: all |Φ Φ̃⁻¹| ≤ threshold.
            let inv = phi.select_rows(&sel.rows).partial_piv_lu().inverse();
            let b = phi.matrix() * &inv;
            for i in 0..n {
                for k in 0..r {
                    assert!(b[(i, k)].abs() <= SWAP_THRESHOLD + 1e-9);
                }
            }
        }
    }

    #[test]
    fn errors_on_short_or_rank_deficient() {
        let phi = phi_from_fn(2, 3, |i, k| (i + k) as f64);
        assert!(matches!(
            select_maxvol_rows(&phi),
            Err(RigError::SizeMismatch { .. })
        ));
        // Column 2 = column 0 + column 1.
        let phi = phi_from_fn(10, 3, |i, k| {
            let a = (i as f64).sin();
            let b = (i as f64 * 1.7).cos();
            [a, b, a + b][k]
        });
        assert!(matches!(
            select_maxvol_rows(&phi),
            Err(RigError::Singular { .. })
        ));
        let phi = phi_from_fn(4, 2, |i, k| if i == k { 1.0 } else { 0.5 });
        assert!(log_abs_det_of_rows(&phi, &[0]).is_err());
        assert!(log_abs_det_of_rows(&phi, &[0, 9]).is_err());
        assert!((log_abs_det_of_rows(&phi, &[0, 1]).unwrap() - 0.75f64.ln()).abs() < 1e-14);
    }
}
