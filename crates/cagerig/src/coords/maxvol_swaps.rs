//! The swap refinement of MaxVol (see [`super::maxvol`]) on B = Φ Φ̃⁻¹ (`#V × #C`; rows of the
//! selection Φ̃ are rows of the identity in B):
//!
//! - single swaps: replacing the selected row of column j by row i multiplies |det Φ̃| by
//!   |B[i, j]|; B is updated by the rank-1 formula `B ← B − B[:, j] (B[i, :] − e_jᵀ) / B[i, j]`
//!   fused with the next argmax |B| (one vectorised pass, parallel over row blocks when B is big);
//! - pair swaps: rows i1, i2 into columns j1, j2 at once multiply |det Φ̃| by
//!   |B[i1,j1] B[i2,j2] − B[i1,j2] B[i2,j1]|, which can exceed 1 at a single-swap local maximum
//!   (two rows that each share two cage vertices). Searching them lifts the refinement out of
//!   most poor local maxima at the cost of a scan of B, where restarts from other greedy
//!   initialisations cost a factorisation and a product each.

use faer::Mat;
use rayon::prelude::*;

use super::maxvol::{MaxVolSelection, log_abs_det_of_rows};
use super::maxvol_lu::{SWAP_THRESHOLD, SeqLu};
use crate::cage_coords::CageCoords;
use crate::error::RigError;

/// Safety cap on swaps per cage vertex.
const MAX_SWAPS_PER_COLUMN: usize = 100;
/// B matrices with fewer entries are refined sequentially: a swap on the Arm (121k entries)
/// takes ~50 µs, and waking the rayon workers for each one made it slower (2 threads: 3.3 ms
/// against 2.4 ms for the whole selection).
const PARALLEL_ENTRIES: usize = 1 << 20;
/// Most rows per parallel task of the rank-1 update.
#[cfg(not(target_arch = "wasm32"))]
const ROW_BLOCK: usize = 8192;
/// Fewest rows per parallel task of the rank-1 update.
#[cfg(not(target_arch = "wasm32"))]
const MIN_ROW_BLOCK: usize = 256;
/// Pair swaps are searched among rows with |B[i, j]| ≥ this in both columns: a pair swap
/// that improves on a single-swap maximum (all |B| ≤ 1) needs two rows spread over the same
/// two columns.
const PAIR_ENTRY_FLOOR: f64 = 0.25;

/// Greedy single swaps from `initial_rows` (`#C` distinct rows of Φ) until every |B[i, j]| ≤
/// [`SWAP_THRESHOLD`]; returns the selection and its B. Errors if a row is out of range or the
/// initial submatrix is singular.
pub(crate) fn refine(
    phi: &CageCoords,
    initial_rows: &[usize],
) -> Result<(MaxVolSelection, Mat<f64>), RigError> {
    let (mut b, mut scratch) = initial_b(phi, initial_rows)?;
    let mut rows = initial_rows.to_vec();
    let best = scratch.argmax(&mut b);
    let (swaps, _) = climb(&mut b, &mut rows, best, &mut scratch);
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

/// [`refine`], then pair swaps (each followed by single swaps) while one improves |det Φ̃|.
/// The result is dominant on all rows of Φ (every |B[i, j]| ≤ [`SWAP_THRESHOLD`]).
pub(crate) fn local_search(
    phi: &CageCoords,
    initial_rows: &[usize],
) -> Result<MaxVolSelection, RigError> {
    let (mut b, mut scratch) = initial_b(phi, initial_rows)?;
    let mut rows = initial_rows.to_vec();
    let best = scratch.argmax(&mut b);
    let (mut swaps, _) = climb(&mut b, &mut rows, best, &mut scratch);
    let limit = MAX_SWAPS_PER_COLUMN * rows.len();
    let mut pairs = PairScratch::default();
    while swaps < limit {
        let Some((first, second)) = best_pair_swap(&b, &mut pairs) else {
            break;
        };
        swap_row(&mut b, &mut rows, first, &mut scratch);
        let (next, _) = swap_row(&mut b, &mut rows, second, &mut scratch);
        let (more, _) = climb(&mut b, &mut rows, next, &mut scratch);
        swaps += 2 + more;
    }
    let log_abs_det = log_abs_det_of_rows(phi, &rows)?;
    Ok(MaxVolSelection {
        rows,
        log_abs_det,
        swaps,
    })
}

/// B = Φ Φ̃⁻¹ for the selection `rows` and the swap buffers. Errors if a row is out of range or
/// the submatrix is singular.
fn initial_b(phi: &CageCoords, rows: &[usize]) -> Result<(Mat<f64>, SwapScratch), RigError> {
    let initial_log_det = log_abs_det_of_rows(phi, rows)?;
    if !initial_log_det.is_finite() {
        return Err(RigError::Singular {
            what: "initial MaxVol submatrix",
        });
    }
    let matrix = phi.matrix();
    let (num_rows, rank) = (matrix.nrows(), matrix.ncols());
    let inverse = SeqLu::new(phi.select_rows(rows)).inverse();
    // Small problems run sequentially.
    let parallel = num_rows * rank >= PARALLEL_ENTRIES && rayon::current_num_threads() > 1;
    crate::memory_estimate::check_table_allocation("MaxVol: B = ΦΦ̃⁻¹", num_rows, "rows", rank)?;
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
    Ok((b, SwapScratch::new(num_rows, rank, parallel)))
}

/// Buffers of [`swap_row`] and whether B is updated in parallel.
struct SwapScratch {
    pivot_column: Vec<f64>,
    pivot_row: Vec<f64>,
    parallel: bool,
}

impl SwapScratch {
    fn new(num_rows: usize, rank: usize, parallel: bool) -> Self {
        Self {
            pivot_column: vec![0.0; num_rows],
            pivot_row: vec![0.0; rank],
            parallel,
        }
    }

    /// (row, column, |value|) of the largest |B[i, k]|.
    fn argmax(&mut self, b: &mut Mat<f64>) -> (usize, usize, f64) {
        if self.parallel {
            argmax_abs(b)
        } else {
            // A zero update: just the argmax.
            self.pivot_column.fill(0.0);
            self.pivot_row.fill(0.0);
            rank_one_update_and_argmax_seq(b, &self.pivot_column, &self.pivot_row)
        }
    }
}

/// Replaces the selected row of column j by row i (B[i, j] ≠ 0): |det Φ̃| is multiplied by
/// |B[i, j]|. Returns the new argmax |B| and ln |B[i, j]|.
fn swap_row(
    b: &mut Mat<f64>,
    rows: &mut [usize],
    (i, j): (usize, usize),
    scratch: &mut SwapScratch,
) -> ((usize, usize, f64), f64) {
    let pivot = b[(i, j)];
    scratch.pivot_column.copy_from_slice(column(b, j));
    for (k, r) in scratch.pivot_row.iter_mut().enumerate() {
        *r = (b[(i, k)] - if k == j { 1.0 } else { 0.0 }) / pivot;
    }
    rows[j] = i;
    let best = if scratch.parallel {
        rank_one_update_and_argmax(b, &scratch.pivot_column, &scratch.pivot_row)
    } else {
        rank_one_update_and_argmax_seq(b, &scratch.pivot_column, &scratch.pivot_row)
    };
    (best, pivot.abs().ln())
}

/// Greedy single swaps from `best` (the current argmax |B|) while it exceeds
/// [`SWAP_THRESHOLD`]: (swaps, ln of the |det Φ̃| growth).
fn climb(
    b: &mut Mat<f64>,
    rows: &mut [usize],
    mut best: (usize, usize, f64),
    scratch: &mut SwapScratch,
) -> (usize, f64) {
    let (mut swaps, mut gain) = (0, 0.0);
    let limit = MAX_SWAPS_PER_COLUMN * rows.len();
    while best.2 > SWAP_THRESHOLD && swaps < limit {
        let (next, log_factor) = swap_row(b, rows, (best.0, best.1), scratch);
        best = next;
        gain += log_factor;
        swaps += 1;
    }
    (swaps, gain)
}

/// Scratch of [`best_pair_swap`].
#[derive(Default)]
struct PairScratch {
    /// Counting-sort offsets: per row (then per column pair), where its items start.
    starts: Vec<u32>,
    /// Fill positions of the counting sorts.
    next: Vec<u32>,
    /// Columns of the significant entries (|B| ≥ [`PAIR_ENTRY_FLOOR`]), by row.
    columns: Vec<u32>,
    /// Per row and pair j1 < j2 of its significant columns: (j1·#C + j2, row).
    shared: Vec<(u32, u32)>,
    /// `shared` grouped by column pair: rows, B[row, j1], B[row, j2].
    group_rows: Vec<u32>,
    group_x: Vec<f64>,
    group_y: Vec<f64>,
}

/// Stable counting sort of `keys.len()` items by key (< `buckets`): fills `starts`
/// (`buckets + 1` offsets) and calls `place(item, slot)` for each item.
fn counting_sort(
    keys: impl Iterator<Item = usize> + Clone,
    buckets: usize,
    starts: &mut Vec<u32>,
    next: &mut Vec<u32>,
    mut place: impl FnMut(usize, usize),
) {
    starts.clear();
    starts.resize(buckets + 1, 0);
    for key in keys.clone() {
        starts[key + 1] += 1;
    }
    for b in 0..buckets {
        starts[b + 1] += starts[b];
    }
    next.clear();
    next.extend_from_slice(&starts[..buckets]);
    for (item, key) in keys.enumerate() {
        place(item, next[key] as usize);
        next[key] += 1;
    }
}

/// The pair swap (row i1 into column j1, then row i2 into column j2) with the largest |det Φ̃|
/// factor |B[i1,j1] B[i2,j2] − B[i1,j2] B[i2,j1]| among rows with |B| ≥ [`PAIR_ENTRY_FLOOR`] in
/// both columns, if that factor exceeds [`SWAP_THRESHOLD`] (ties: the first found). Of the four
/// orders of the two swaps, the one whose first pivot is largest.
fn best_pair_swap(
    b: &Mat<f64>,
    scratch: &mut PairScratch,
) -> Option<((usize, usize), (usize, usize))> {
    let (num_rows, rank) = (b.nrows(), b.ncols());
    let PairScratch {
        starts,
        next,
        columns,
        shared,
        group_rows,
        group_x,
        group_y,
    } = scratch;
    // Significant entries by row: count per row, then place (contiguous column scans).
    starts.clear();
    starts.resize(num_rows + 1, 0);
    for k in 0..rank {
        for (count, v) in starts[1..].iter_mut().zip(column(b, k)) {
            *count += u32::from(v.abs() >= PAIR_ENTRY_FLOOR);
        }
    }
    for i in 0..num_rows {
        starts[i + 1] += starts[i];
    }
    columns.clear();
    columns.resize(starts[num_rows] as usize, 0);
    next.clear();
    next.extend_from_slice(&starts[..num_rows]);
    for k in 0..rank {
        for (i, v) in column(b, k).iter().enumerate() {
            if v.abs() >= PAIR_ENTRY_FLOOR {
                columns[next[i] as usize] = k as u32;
                next[i] += 1;
            }
        }
    }
    // Rows sharing two columns, grouped by the column pair.
    shared.clear();
    for i in 0..num_rows {
        let row = &columns[starts[i] as usize..starts[i + 1] as usize];
        for (x, &j1) in row.iter().enumerate() {
            for &j2 in &row[x + 1..] {
                shared.push((j1 * rank as u32 + j2, i as u32));
            }
        }
    }
    for group in [&mut *group_x, &mut *group_y] {
        group.clear();
        group.resize(shared.len(), 0.0);
    }
    group_rows.clear();
    group_rows.resize(shared.len(), 0);
    counting_sort(
        shared.iter().map(|e| e.0 as usize),
        rank * rank,
        starts,
        next,
        |item, slot| {
            let (key, i) = shared[item];
            let (j1, j2) = (key as usize / rank, key as usize % rank);
            group_rows[slot] = i;
            group_x[slot] = b[(i as usize, j1)];
            group_y[slot] = b[(i as usize, j2)];
        },
    );
    // Per group, per first row: the largest factor over the later rows (a vectorised max), and
    // where it is only when it beats the best so far.
    let mut best: Option<(usize, usize, usize, f64)> = None;
    for key in 0..rank * rank {
        let range = starts[key] as usize..starts[key + 1] as usize;
        let (xs, ys) = (&group_x[range.clone()], &group_y[range]);
        for (x, (&x1, &y1)) in xs.iter().zip(ys).enumerate() {
            let largest = xs[x + 1..]
                .iter()
                .zip(&ys[x + 1..])
                .map(|(&x2, &y2)| (x1 * y2 - y1 * x2).abs())
                .fold(0.0f64, f64::max);
            let floor = best.map_or(SWAP_THRESHOLD, |t| t.3);
            if largest > floor
                && let Some(z) =
                    (x + 1..xs.len()).find(|&z| (x1 * ys[z] - y1 * xs[z]).abs() == largest)
            {
                best = Some((key, x, z, largest));
            }
        }
    }
    let (key, x, z, _) = best?;
    let group = &group_rows[starts[key] as usize..];
    let (i1, i2) = (group[x] as usize, group[z] as usize);
    let (j1, j2) = (key / rank, key % rank);
    let orders = [
        ((i1, j1), (i2, j2)),
        ((i2, j2), (i1, j1)),
        ((i1, j2), (i2, j1)),
        ((i2, j1), (i1, j2)),
    ];
    Some(orders.iter().copied().fold(
        orders[0],
        |m, o| {
            if b[o.0].abs() > b[m.0].abs() { o } else { m }
        },
    ))
}

/// Column k of a column-major owned matrix as a slice.
pub(crate) fn column(m: &Mat<f64>, k: usize) -> &[f64] {
    m.col(k)
        .try_as_col_major()
        .map(|c| c.as_slice())
        .unwrap_or(&[])
}

/// (row, column, |value|) of the entry with the largest magnitude (first row, then first column,
/// on ties).
fn argmax_abs(b: &Mat<f64>) -> (usize, usize, f64) {
    (0..b.ncols())
        .into_par_iter()
        .map(|k| match first_max_abs(column(b, k), -1.0) {
            Some((i, value)) => (i, k, value),
            None => (0, k, -1.0),
        })
        .reduce(|| (0, 0, -1.0), max_entry)
}

/// Lanes of the vectorised column scans.
const SCAN_LANES: usize = 8;

/// Lane-wise `max |v|` (vectorises: no loop-carried index); NaN entries are ignored.
#[inline]
fn lane_max_abs(lanes: &mut [f64; SCAN_LANES], values: &[f64; SCAN_LANES]) {
    for (m, v) in lanes.iter_mut().zip(values) {
        let a = v.abs();
        *m = if a > *m { a } else { *m };
    }
}

/// (index, |value|) of the first entry of `column` with the largest magnitude, if that magnitude
/// exceeds `floor`. The maximum is found lane-wise, the index by a second scan (only when needed).
#[inline]
fn first_max_abs(column: &[f64], floor: f64) -> Option<(usize, f64)> {
    let mut lanes = [0.0f64; SCAN_LANES];
    let mut chunks = column.chunks_exact(SCAN_LANES);
    for chunk in &mut chunks {
        lane_max_abs(&mut lanes, chunk.try_into().unwrap_or(&[0.0; SCAN_LANES]));
    }
    finish_max_abs(column, lanes, chunks.remainder(), floor)
}

/// Folds the lanes and the tail, then locates the maximum (see [`first_max_abs`]).
#[inline]
fn finish_max_abs(
    column: &[f64],
    lanes: [f64; SCAN_LANES],
    tail: &[f64],
    floor: f64,
) -> Option<(usize, f64)> {
    let largest = lanes
        .iter()
        .chain(tail)
        .map(|v| v.abs())
        .fold(0.0f64, |m, a| if a > m { a } else { m });
    if largest <= floor || column.is_empty() {
        return None;
    }
    column
        .iter()
        .position(|v| v.abs() == largest)
        .map(|i| (i, largest))
}

/// `column -= source · factor`, then [`first_max_abs`] of the result (one vectorised pass).
#[inline]
fn update_and_first_max_abs(
    column: &mut [f64],
    source: &[f64],
    factor: f64,
    floor: f64,
) -> Option<(usize, f64)> {
    let mut lanes = [0.0f64; SCAN_LANES];
    let mut chunks = column.chunks_exact_mut(SCAN_LANES);
    let mut sources = source.chunks_exact(SCAN_LANES);
    for (chunk, src) in (&mut chunks).zip(&mut sources) {
        for (v, s) in chunk.iter_mut().zip(src) {
            *v -= s * factor;
        }
        lane_max_abs(
            &mut lanes,
            chunk.as_ref().try_into().unwrap_or(&[0.0; SCAN_LANES]),
        );
    }
    let tail = chunks.into_remainder();
    for (v, s) in tail.iter_mut().zip(sources.remainder()) {
        *v -= s * factor;
    }
    let tail_len = tail.len();
    let tail = &column[column.len() - tail_len..];
    finish_max_abs(column, lanes, tail, floor)
}

/// The larger of two (row, column, |value|) entries; on ties the first column, then the first
/// row — the order of the sequential scan, so that any split into row blocks gives its result.
fn max_entry(a: (usize, usize, f64), b: (usize, usize, f64)) -> (usize, usize, f64) {
    if b.2 > a.2 || (b.2 == a.2 && (b.1, b.0) < (a.1, a.0)) {
        b
    } else {
        a
    }
}

/// `B[:, k] -= pivot_column · pivot_row[k]` for every k, returning the new argmax |B|.
#[cfg(not(target_arch = "wasm32"))]
fn rank_one_update_and_argmax(
    b: &mut Mat<f64>,
    pivot_column: &[f64],
    pivot_row: &[f64],
) -> (usize, usize, f64) {
    // One task per thread on B that fits the caches, blocks of ROW_BLOCK rows beyond.
    let row_block = b
        .nrows()
        .div_ceil(rayon::current_num_threads())
        .clamp(MIN_ROW_BLOCK, ROW_BLOCK);
    b.par_row_chunks_mut(row_block)
        .enumerate()
        .map(|(block, chunk)| {
            let start = block * row_block;
            let source = &pivot_column[start..start + chunk.nrows()];
            let (r, k, value) = update_block_and_argmax(chunk, source, pivot_row);
            (start + r, k, value)
        })
        .reduce(|| (0, 0, -1.0), max_entry)
}

/// The web target has no threads: [`rank_one_update_and_argmax_seq`], the same argmax (ties are
/// broken by position, whatever the split).
#[cfg(target_arch = "wasm32")]
fn rank_one_update_and_argmax(
    b: &mut Mat<f64>,
    pivot_column: &[f64],
    pivot_row: &[f64],
) -> (usize, usize, f64) {
    rank_one_update_and_argmax_seq(b, pivot_column, pivot_row)
}

/// Sequential [`rank_one_update_and_argmax`] (a zero `pivot_row` just finds the argmax).
fn rank_one_update_and_argmax_seq(
    b: &mut Mat<f64>,
    pivot_column: &[f64],
    pivot_row: &[f64],
) -> (usize, usize, f64) {
    update_block_and_argmax(b.as_mut(), pivot_column, pivot_row)
}

/// `B[:, k] -= pivot_column · pivot_row[k]` on a block of rows of B (`pivot_column` the same
/// rows), returning the block's argmax |B| (row within the block; first column, then first row
/// on ties).
fn update_block_and_argmax(
    mut b: faer::MatMut<'_, f64>,
    pivot_column: &[f64],
    pivot_row: &[f64],
) -> (usize, usize, f64) {
    let mut best = (0, 0, -1.0);
    for (k, &factor) in pivot_row.iter().enumerate() {
        let Some(col) = b.as_mut().col_mut(k).try_as_col_major_mut() else {
            continue;
        };
        if let Some((r, value)) =
            update_and_first_max_abs(col.as_slice_mut(), pivot_column, factor, best.2)
        {
            best = (r, k, value);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use faer::linalg::solvers::DenseSolveCore;

    fn phi_from_rows(rows: &[[f64; 2]]) -> CageCoords {
        CageCoords::from_matrix(Mat::from_fn(rows.len(), 2, |i, k| rows[i][k])).unwrap()
    }

    #[test]
    fn pair_swap_escapes_a_single_swap_maximum() {
        // From rows {0, 1} (Φ̃ = I), B = Φ: every |B| ≤ 1, so no single swap helps, but rows
        // {2, 3} have |det| = 0.9·0.9 + 0.6·0.6 = 1.17.
        let phi = phi_from_rows(&[[1.0, 0.0], [0.0, 1.0], [0.9, -0.6], [0.6, 0.9]]);
        let single = refine(&phi, &[0, 1]).unwrap().0;
        assert_eq!(single.rows, vec![0, 1]);
        assert_eq!(single.swaps, 0);
        let paired = local_search(&phi, &[0, 1]).unwrap();
        let mut rows = paired.rows.clone();
        rows.sort_unstable();
        assert_eq!(rows, vec![2, 3]);
        assert!((paired.log_abs_det - 1.17f64.ln()).abs() < 1e-12);
    }

    #[test]
    fn no_pair_swap_at_a_pair_maximum() {
        // Rows 2, 3 share both columns but |0.5·0.5 − 0.5·0.4| < 1.
        let phi = phi_from_rows(&[[1.0, 0.0], [0.0, 1.0], [0.5, 0.5], [0.4, 0.5]]);
        let (_, b) = refine(&phi, &[0, 1]).unwrap();
        assert_eq!(best_pair_swap(&b, &mut PairScratch::default()), None);
        let paired = local_search(&phi, &[0, 1]).unwrap();
        assert_eq!(paired.rows, vec![0, 1]);
    }

    #[test]
    fn local_search_is_dominant_and_not_worse_than_single_swaps() {
        let mut state = 7u64;
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        for _ in 0..30 {
            let (n, r) = (40, 5);
            let values: Vec<f64> = (0..n * r).map(|_| rnd()).collect();
            let phi =
                CageCoords::from_matrix(Mat::from_fn(n, r, |i, k| values[i * r + k])).unwrap();
            let initial: Vec<usize> = (0..r).collect();
            let single = refine(&phi, &initial).unwrap().0;
            let paired = local_search(&phi, &initial).unwrap();
            assert!(paired.log_abs_det >= single.log_abs_det - 1e-12);
            let inverse = phi.select_rows(&paired.rows).partial_piv_lu().inverse();
            let b = phi.matrix() * &inverse;
            for k in 0..r {
                for i in 0..n {
                    assert!(b[(i, k)].abs() <= SWAP_THRESHOLD + 1e-9);
                }
            }
        }
    }

    #[test]
    fn parallel_and_sequential_updates_agree_including_ties() {
        // Exact ties (repeated rows) in several row blocks: both pick the first column, then the
        // first row.
        let (n, r) = (3 * MIN_ROW_BLOCK + 17, 4);
        let value = |i: usize, k: usize| (((i % 97) * 31 + k * 7) % 13) as f64 - 6.0;
        let mut par = Mat::from_fn(n, r, value);
        let mut seq = par.clone();
        let pivot_column: Vec<f64> = (0..n).map(|i| ((i % 5) as f64) * 0.25).collect();
        let pivot_row = vec![0.5, -1.0, 0.0, 2.0];
        let a = rank_one_update_and_argmax(&mut par, &pivot_column, &pivot_row);
        let b = rank_one_update_and_argmax_seq(&mut seq, &pivot_column, &pivot_row);
        assert_eq!(a, b);
        assert_eq!(par, seq);
        assert_eq!(argmax_abs(&par), b);
    }
}
