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

/// The extra starts use, per column k, the rows with the [`CANDIDATES_PER_COLUMN`] largest
/// |B[i, k]| after the first start (B = Φ Φ̃⁻¹): rows that are well represented by the first
/// selection cannot matter much. This keeps the extra starts independent of #V.
pub const CANDIDATES_PER_COLUMN: usize = 32;

/// [`select_maxvol_rows_with`] with the default options.
pub fn select_maxvol_rows(phi: &CageCoords) -> Result<MaxVolSelection, RigError> {
    select_maxvol_rows_with(phi, &MaxVolOptions::default())
}

/// Selects #C rows of Φ (`#V × #C`) with locally maximal |det| (see module docs), the best of
/// `options.starts` greedy starts, finally refined on all rows (so the result is dominant on Φ).
/// Errors if #V < #C or Φ is (numerically) rank deficient.
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
    let first_rows = lu_pivot_rows(matrix, None, scale)?;
    let (mut best, b) = refine(phi, &first_rows)?;
    if options.starts <= 1 {
        return Ok(best);
    }
    // Extra starts on the candidate rows: per column, the rows with the largest |B[:, k]|.
    let candidates = candidate_rows(&b);
    drop(b);
    let reduced = CageCoords::from_matrix(phi.select_rows(&candidates))?;
    let mut state = options.seed;
    let mut improved = false;
    for _ in 1..options.starts {
        let mut order: Vec<usize> = (0..rank).collect();
        for i in (1..rank).rev() {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            order.swap(i, (state >> 33) as usize % (i + 1));
        }
        let Ok(local_rows) = lu_pivot_rows(reduced.matrix(), Some(&order), scale) else {
            continue;
        };
        let Ok((local, _)) = refine(&reduced, &local_rows) else {
            continue;
        };
        if local.log_abs_det > best.log_abs_det {
            best = MaxVolSelection {
                rows: local.rows.iter().map(|&r| candidates[r]).collect(),
                log_abs_det: local.log_abs_det,
                swaps: local.swaps,
            };
            improved = true;
        }
    }
    if improved {
        // Make the winner dominant on all rows (usually zero swaps).
        let swaps = best.swaps;
        let (mut full, _) = refine(phi, &best.rows)?;
        full.swaps += swaps;
        best = full;
    }
    Ok(best)
}

/// Union over columns k of the rows with the largest |B[i, k]|, sorted.
fn candidate_rows(b: &Mat<f64>) -> Vec<usize> {
    let mut rows: Vec<usize> = (0..b.ncols())
        .into_par_iter()
        .flat_map_iter(|k| {
            let col = column(b, k);
            let mut order: Vec<usize> = (0..col.len()).collect();
            let m = CANDIDATES_PER_COLUMN.min(col.len());
            if m < col.len() {
                order.select_nth_unstable_by(m, |&x, &y| col[y].abs().total_cmp(&col[x].abs()));
                order.truncate(m);
            }
            order
        })
        .collect();
    rows.sort_unstable();
    rows.dedup();
    rows
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
    let mut b: Mat<f64> = matrix * &inverse;
    let mut pivot_column = vec![0.0; num_rows];
    let mut pivot_row = vec![0.0; rank];
    let mut swaps = 0;
    let mut best = argmax_abs(&b);
    while best.2 > SWAP_THRESHOLD && swaps < MAX_SWAPS_PER_COLUMN * rank {
        let (i, j, _) = best;
        let pivot = b[(i, j)];
        pivot_column.copy_from_slice(column(&b, j));
        for (k, r) in pivot_row.iter_mut().enumerate() {
            *r = (b[(i, k)] - if k == j { 1.0 } else { 0.0 }) / pivot;
        }
        rows[j] = i;
        swaps += 1;
        best = rank_one_update_and_argmax(&mut b, &pivot_column, &pivot_row);
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
