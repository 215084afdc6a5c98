//! MaxVol row selection (Goreinov, Oseledets, Savostyanov, Tyrtyshnikov et al. 2010; used by
//! Thiery et al. 2012 and by CageUp/CageRev): choose #C rows of the cage coordinates Φ
//! (`#V × #C`) whose square submatrix Φ̃ (`#C × #C`) has a (locally) maximal |det Φ̃|.
//!
//! 1. Initial rows: LU with partial (row) pivoting of Φ (greedy: each pivot is the row with the
//!    largest remaining entry in the next column), via faer.
//! 2. Refinement ([`super::maxvol_swaps`]): B = Φ Φ̃⁻¹ (`#V × #C`, B restricted to the selected
//!    rows is the identity). While the largest |B[i, j]| exceeds [`SWAP_THRESHOLD`], replace
//!    selected row j by row i (|det Φ̃| grows by |B[i, j]|, B is updated by a rank-1 formula);
//!    at such a single-swap maximum, look for a pair swap that still grows |det Φ̃| and climb
//!    again from it.
//! 3. Small Φ (at most [`ALL_ROWS_ENTRIES`] entries) are refined on all rows at once. On big Φ
//!    the refinement runs on candidate rows (the [`CANDIDATES_PER_COLUMN`] largest |Φ[i, k]| of
//!    every column), then dominance checks over all rows ([`super::maxvol_dominance`]) add the
//!    rows that violate the bound and the refinement continues, until none does.
//! 4. Multi-start ([`MaxVolOptions::starts`]): further greedy initialisations (LU with shuffled
//!    column orders), the best result kept.
//!
//! At convergence every row of Φ is a combination of the selected rows with coefficients of
//! magnitude ≤ [`SWAP_THRESHOLD`] (a "dominant" submatrix).

use faer::Mat;
use rayon::prelude::*;

use super::maxvol_dominance::dominance_violations;
use super::maxvol_swaps::{local_search, refine};
use crate::cage_coords::CageCoords;
use crate::error::RigError;
use crate::memory_estimate::check_table_allocation;

pub use super::maxvol_lu::SWAP_THRESHOLD;
pub(crate) use super::maxvol_lu::SeqLu;

/// Φ with at most this many entries (`#V·#C`; 4 MB of B, within L3) are refined on all rows
/// at once: the result needs no dominance check (Arm: 121k entries; subdivided once: 483k).
pub const ALL_ROWS_ENTRIES: usize = 1 << 19;

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
    /// Greedy starts (≥ 1) on big Φ, which run on the candidate rows (their cost does not grow
    /// with #V; the dominance checks over all rows dominate). Start 0 uses the LU pivot rows;
    /// the others use LU with deterministically shuffled column orders; each is refined with
    /// single and pair swaps and the best on the candidates is kept (the dominance rounds that
    /// follow may still end lower than from another start). Default 4: on the Arm subdivided
    /// 2, 3 and 4 times, ln |det Φ̃| is then that of 16 single-swap starts (−49.0146,
    /// −48.9336, −48.7879); one start gives −49.0144, −48.9340, −48.7911.
    pub starts: usize,
    /// Greedy starts (≥ 1) on small Φ (≤ [`ALL_ROWS_ENTRIES`] entries), refined on all rows.
    /// Default 1: with pair swaps one start reaches what 16 starts of single-swap refinement
    /// found, measured as ln |det Φ̃| on the Arm (−49.3763, equal) and the Arm subdivided once
    /// (−49.0079 against −49.1073), at a tenth of the time.
    pub starts_all_rows: usize,
    /// Seed of the column shuffles.
    pub seed: u64,
}

impl Default for MaxVolOptions {
    fn default() -> Self {
        Self {
            starts: 4,
            starts_all_rows: 1,
            seed: 0x5eed,
        }
    }
}

/// What [`RigError::Singular`] names when no #C rows of Φ are independent: the mesh gives the
/// cage no #C vertices to be fitted on, in a modeller's words.
const MAXVOL_RANK_DEFICIENT: &str = "the cage coordinates Φ of the mesh (the rig fits the cage's \
     #C vertices to #C mesh vertices with independent coordinates, and this mesh has none: it is \
     flat, or has fewer distinct vertex positions than the cage has vertices; use a cage with \
     fewer vertices, or a mesh with more; `cagerig cage` checks this), whose MaxVol block";

/// Candidate rows on big Φ: per column k, the rows with the [`CANDIDATES_PER_COLUMN`] largest
/// |Φ[i, k]| (a row interpolating cage vertex k is one where Φ[:, k] dominates). The starts run
/// on the candidates only, which keeps them independent of #V.
pub const CANDIDATES_PER_COLUMN: usize = 32;

/// [`select_maxvol_rows_with`] with the default options.
pub fn select_maxvol_rows(phi: &CageCoords) -> Result<MaxVolSelection, RigError> {
    select_maxvol_rows_with(phi, &MaxVolOptions::default())
}

/// Selects #C rows of Φ (`#V × #C`) with locally maximal |det| (see module docs), the best of
/// `options.starts` (`options.starts_all_rows` on small Φ) greedy starts, made dominant on all
/// rows of Φ.
///
/// Small Φ (≤ [`ALL_ROWS_ENTRIES`] entries): the starts run on all rows. Big Φ: the starts run
/// on candidate rows (see [`CANDIDATES_PER_COLUMN`]); then one pass over Φ computes B = Φ Φ̃⁻¹
/// block by block. Rows with some |B[i, j]| > [`SWAP_THRESHOLD`] join the candidates and the
/// refinement continues from the current best, until no row of Φ violates the bound. Errors if
/// #V < #C or Φ is (numerically) rank deficient.
pub fn select_maxvol_rows_with(
    phi: &CageCoords,
    options: &MaxVolOptions,
) -> Result<MaxVolSelection, RigError> {
    let selection = maxvol_selection(phi, options);
    // Its faer factorisations and products ran on this thread and on the pool's.
    crate::vector_registers::clear_upper_halves_everywhere();
    selection
}

/// The work of [`select_maxvol_rows_with`].
fn maxvol_selection(
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
    if num_rows * rank <= ALL_ROWS_ENTRIES {
        let scale = (0..rank)
            .flat_map(|k| phi.column(k).iter())
            .fold(0.0f64, |m, v| m.max(v.abs()));
        let first_rows = lu_pivot_rows(matrix, None, scale)?;
        return best_of_starts(
            phi,
            &first_rows,
            scale,
            options.starts_all_rows,
            options.seed,
        );
    }
    let (mut candidates, scale) = top_rows_per_column(phi, CANDIDATES_PER_COLUMN);
    let reduced = candidate_rows(phi, &candidates)?;
    // Start 0: LU pivots of the candidates (of all rows if the candidates are rank deficient).
    let first_rows: Vec<usize> = match lu_pivot_rows(reduced.matrix(), None, scale) {
        Ok(local) => local.iter().map(|&r| candidates[r]).collect(),
        Err(_) => {
            check_table_allocation("MaxVol: LU of all of Φ", num_rows, "vertices", rank)?;
            let rows = lu_pivot_rows(matrix, None, scale)?;
            candidates = merged(&candidates, &rows);
            rows
        }
    };
    let local_rows = |candidates: &[usize], rows: &[usize]| -> Vec<usize> {
        rows.iter()
            .filter_map(|r| candidates.binary_search(r).ok())
            .collect()
    };
    // Round 1: the starts on the candidates.
    let reduced = candidate_rows(phi, &candidates)?;
    let local = best_of_starts(
        &reduced,
        &local_rows(&candidates, &first_rows),
        scale,
        options.starts,
        options.seed,
    )?;
    let mut best = MaxVolSelection {
        rows: local.rows.iter().map(|&r| candidates[r]).collect(),
        log_abs_det: local.log_abs_det,
        swaps: local.swaps,
    };
    // Later rounds: add the rows of Φ that violate dominance, refine from the current best.
    let mut bounds = None;
    loop {
        let violators =
            dominance_violations(phi, &best.rows, &mut bounds, CANDIDATES_PER_COLUMN * rank)?;
        let before = candidates.len();
        candidates = merged(&candidates, &violators);
        if candidates.len() == before {
            // No violators (or, through rounding at the threshold, only rows the refinement
            // on the candidates already accepted).
            break;
        }
        let reduced = candidate_rows(phi, &candidates)?;
        let (local, _) = refine(&reduced, &local_rows(&candidates, &best.rows))?;
        best = MaxVolSelection {
            rows: local.rows.iter().map(|&r| candidates[r]).collect(),
            log_abs_det: local.log_abs_det,
            swaps: best.swaps + local.swaps,
        };
    }
    Ok(best)
}

/// The rows `candidates` of Φ (`#candidates × #C`), allocated only if the system can spare
/// them and the refinement's B of the same size.
fn candidate_rows(phi: &CageCoords, candidates: &[usize]) -> Result<CageCoords, RigError> {
    let rank = phi.num_cage_vertices();
    check_table_allocation(
        "MaxVol: candidate rows of Φ and their B = ΦΦ̃⁻¹",
        2 * candidates.len(),
        "rows",
        rank,
    )?;
    CageCoords::from_matrix(phi.select_rows(candidates))
}

/// The best (first on ties) of `starts` local searches on Φ: from `first_rows`, then from the
/// LU pivots of column orders shuffled from `seed` (in parallel).
fn best_of_starts(
    phi: &CageCoords,
    first_rows: &[usize],
    scale: f64,
    starts: usize,
    seed: u64,
) -> Result<MaxVolSelection, RigError> {
    let rank = phi.num_cage_vertices();
    // Each start holds an LU copy and a B of Φ's size.
    check_table_allocation(
        "MaxVol: the starts' LU and B tables",
        phi.num_vertices()
            .saturating_mul(2 * starts.clamp(1, rayon::current_num_threads())),
        "rows",
        rank,
    )?;
    let mut state = seed;
    let orders: Vec<Vec<usize>> = (1..starts.max(1))
        .map(|_| {
            let mut order: Vec<usize> = (0..rank).collect();
            for i in (1..rank).rev() {
                state = state
                    .wrapping_mul(6364136223846793005)
                    .wrapping_add(1442695040888963407);
                order.swap(i, (state >> 33) as usize % (i + 1));
            }
            order
        })
        .collect();
    let first = local_search(phi, first_rows);
    let others: Vec<Option<MaxVolSelection>> = orders
        .par_iter()
        .map(|order| {
            let initial = lu_pivot_rows(phi.matrix(), Some(order), scale).ok()?;
            local_search(phi, &initial).ok()
        })
        .collect();
    let mut best = first.ok();
    for local in others.into_iter().flatten() {
        if best
            .as_ref()
            .is_none_or(|b| local.log_abs_det > b.log_abs_det)
        {
            best = Some(local);
        }
    }
    best.ok_or(RigError::Singular {
        what: MAXVOL_RANK_DEFICIENT,
    })
}

/// Sorted union of two row lists (the first sorted and deduplicated).
fn merged(sorted: &[usize], extra: &[usize]) -> Vec<usize> {
    let mut rows: Vec<usize> = sorted.iter().chain(extra).copied().collect();
    rows.sort_unstable();
    rows.dedup();
    rows
}

/// Union over columns k of the `per_column` rows with the largest |Φ[i, k]|, sorted, and
/// max |Φ[i, k]| over all entries.
fn top_rows_per_column(phi: &CageCoords, per_column: usize) -> (Vec<usize>, f64) {
    let rank = phi.num_cage_vertices();
    let kept: Vec<(f64, usize)> = (0..rank)
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
            kept
        })
        .collect();
    let scale = kept.iter().fold(0.0f64, |m, e| m.max(e.0));
    let mut rows: Vec<usize> = kept.into_iter().map(|(_, i)| i).collect();
    rows.sort_unstable();
    rows.dedup();
    (rows, scale)
}

/// The first #C pivot rows of a row-pivoted LU of Φ (columns taken in `order` if given).
fn lu_pivot_rows(
    matrix: &Mat<f64>,
    order: Option<&[usize]>,
    scale: f64,
) -> Result<Vec<usize>, RigError> {
    let rank = matrix.ncols();
    let lu = SeqLu::new(match order {
        Some(order) => Mat::from_fn(matrix.nrows(), rank, |i, k| matrix[(i, order[k])]),
        None => matrix.clone(),
    });
    if lu
        .diagonal()
        .any(|d| d.abs().partial_cmp(&(1e-12 * scale)) != Some(std::cmp::Ordering::Greater))
    {
        return Err(RigError::Singular {
            what: MAXVOL_RANK_DEFICIENT,
        });
    }
    Ok(lu.forward[..rank].to_vec())
}

/// Runs the MaxVol single-swap refinement from the given `#C` distinct rows (see module docs).
/// Errors if the rows are out of range or their submatrix is singular.
pub fn refine_maxvol_rows(
    phi: &CageCoords,
    initial_rows: &[usize],
) -> Result<MaxVolSelection, RigError> {
    let refined = refine(phi, initial_rows).map(|(selection, _)| selection);
    // Its faer products ran on this thread and on the pool's.
    crate::vector_registers::clear_upper_halves_everywhere();
    refined
}

/// ln |det Φ̃| of the `#C × #C` submatrix of the given rows (partial-pivot LU); −∞ when it is
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
    Ok(SeqLu::new(phi.select_rows(rows))
        .diagonal()
        .map(|d| d.abs().ln())
        .sum())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Regression: after MaxVol, SkelUp ran 2× slower on the same threads (36 against 70–75 ms
    /// at Arm N = 3) until a `vzeroupper`. The effect is a speed, measured by the
    /// `skelup_bench` example (Ψ before and after MaxVol); this checks that MaxVol clears the
    /// registers on the calling thread and on every thread of the pool before it returns.
    #[test]
    fn maxvol_clears_every_thread() {
        let (rows, cols) = (4000, 48);
        let matrix = Mat::<f64>::from_fn(rows, cols, |i, k| {
            let x = ((i * 7919 + k * 104_729) % 1009) as f64 / 1009.0;
            x + if i % cols == k { 2.0 } else { 0.0 }
        });
        let phi = CageCoords::from_matrix(matrix).unwrap();
        let (caller, workers) = crate::vector_registers::clear_counts();
        select_maxvol_rows(&phi).unwrap();
        let (caller_after, workers_after) = crate::vector_registers::clear_counts();
        assert!(caller_after > caller, "calling thread");
        assert!(
            workers.iter().zip(&workers_after).all(|(a, b)| b > a),
            "{workers:?} → {workers_after:?}"
        );
    }

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

    use faer::linalg::solvers::DenseSolveCore;

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
