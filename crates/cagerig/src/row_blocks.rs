//! Filling a column-major `rows × cols` f64 matrix (a faer `Mat` made with `with_capacity`) by
//! disjoint row blocks from worker threads, without zero-filling it first: the storage is only
//! ever written, through raw pointers, so the page faults of first touch are spread over the
//! workers instead of a serial zero fill (90 ms for Λ at 532k × 58).

#![expect(
    unsafe_code,
    reason = "matrices filled by disjoint row blocks through raw pointers, without a zero fill"
)]

use std::sync::atomic::{AtomicUsize, Ordering};

use faer::Mat;
use rayon::prelude::*;

/// Progress of `total` rows filled by blocks on worker threads, for a caller's `report(done)`.
/// Each block adds its rows ([`Self::block_done`]) and reports the running count while it is
/// below the total, in whatever order the threads get there; [`Self::finish`], on the calling
/// thread once every block is done, reports the total. So the last report is the whole, however
/// the threads interleave.
pub(crate) struct BlockProgress<'a> {
    report: Option<&'a (dyn Fn(usize) + Sync)>,
    done: AtomicUsize,
    total: usize,
}

impl<'a> BlockProgress<'a> {
    /// No rows done yet of `total`.
    pub(crate) fn new(report: Option<&'a (dyn Fn(usize) + Sync)>, total: usize) -> Self {
        Self {
            report,
            done: AtomicUsize::new(0),
            total,
        }
    }

    /// A block of `rows` rows is done (from any thread).
    pub(crate) fn block_done(&self, rows: usize) {
        let finished = self.done.fetch_add(rows, Ordering::Relaxed) + rows;
        if let Some(report) = self.report
            && finished < self.total
        {
            report(finished);
        }
    }

    /// Every block is done: reports the total.
    pub(crate) fn finish(self) {
        if let Some(report) = self.report {
            report(self.total);
        }
    }
}

/// Fills `N` column-major matrices of `num_rows` rows, matrix i with `num_cols[i]` columns, by
/// disjoint blocks of `block_rows` rows on the worker threads, without zero-filling them first:
/// `fill(scratch, start, blocks)` writes rows `start..start + blocks[i].nrows()` of every
/// matrix, with a `scratch` per worker made by `init`.
///
/// # Safety
/// `fill` must write every entry of every block it is given: the matrices are returned with
/// whatever their storage held where it did not (uninitialised memory).
pub(crate) unsafe fn fill_by_row_blocks<const N: usize, S>(
    num_rows: usize,
    num_cols: [usize; N],
    block_rows: usize,
    init: impl Fn() -> S + Sync + Send,
    fill: impl Fn(&mut S, usize, &mut [RowBlock; N]) + Sync + Send,
) -> [Mat<f64>; N] {
    let mut matrices = num_cols.map(|cols| Mat::<f64>::with_capacity(num_rows, cols));
    let storage: Vec<SharedColumns> = matrices
        .iter_mut()
        .zip(num_cols)
        .map(|(matrix, cols)| SharedColumns::of_capacity(matrix, cols))
        .collect();
    (0..num_rows.div_ceil(block_rows.max(1)))
        .into_par_iter()
        .for_each_init(&init, |scratch, block| {
            let start = block * block_rows;
            let count = block_rows.min(num_rows - start);
            // SAFETY: each allocation holds `col_stride ≥ num_rows` rows for each of its
            // columns; row blocks are disjoint, so no two tasks write the same entry, and
            // nothing reads the storage before the loop ends.
            let mut blocks: [RowBlock; N] =
                std::array::from_fn(|i| unsafe { storage[i].rows(start, count) });
            fill(scratch, start, &mut blocks);
        });
    for (matrix, cols) in matrices.iter_mut().zip(num_cols) {
        // SAFETY: the capacity is (num_rows, cols), and the caller's `fill` wrote every entry
        // of every block (the function's contract).
        unsafe { matrix.set_dims(num_rows, cols) };
    }
    matrices
}

/// The storage of a matrix being filled by row blocks.
struct SharedColumns {
    base: *mut f64,
    col_stride: usize,
    num_cols: usize,
}

// SAFETY: workers only write disjoint row blocks (the contract of `SharedColumns::rows`).
unsafe impl Sync for SharedColumns {}

impl SharedColumns {
    /// The storage of `matrix`, made by `Mat::with_capacity(rows, num_cols)` (its rows are
    /// `col_stride` apart, at least `rows`).
    fn of_capacity(matrix: &mut Mat<f64>, num_cols: usize) -> Self {
        Self {
            base: matrix.as_ptr_mut(),
            col_stride: matrix.col_stride().unsigned_abs(),
            num_cols,
        }
    }

    /// # Safety
    /// Rows `start..start + count` must lie within the capacity and be written by no one else.
    unsafe fn rows(&self, start: usize, count: usize) -> RowBlock {
        // SAFETY: forwarded to the caller.
        unsafe {
            RowBlock::new(
                self.base.wrapping_add(start),
                self.col_stride,
                count,
                self.num_cols,
            )
        }
    }
}

/// Column-major destination for a block of rows of a matrix whose storage may still be
/// uninitialised: only ever written, through raw pointers.
pub(crate) struct RowBlock {
    /// Entry (0, 0) of the block.
    base: *mut f64,
    col_stride: usize,
    nrows: usize,
    ncols: usize,
}

impl RowBlock {
    /// # Safety
    /// For every column `k < ncols`, the `nrows` values from `base + k · col_stride` must be
    /// valid for writes and not accessed through any other pointer while the block lives.
    pub(crate) unsafe fn new(
        base: *mut f64,
        col_stride: usize,
        nrows: usize,
        ncols: usize,
    ) -> Self {
        Self {
            base,
            col_stride,
            nrows,
            ncols,
        }
    }

    pub(crate) fn nrows(&self) -> usize {
        self.nrows
    }

    /// Writes `values` into column `col` from row `row` on.
    #[inline(always)]
    pub(crate) fn write(&mut self, row: usize, col: usize, values: &[f64]) {
        assert!(col < self.ncols && row + values.len() <= self.nrows);
        // SAFETY: in bounds (checked above) of memory the constructor's caller vouched for.
        unsafe {
            let target = self.base.add(col * self.col_stride + row);
            std::ptr::copy_nonoverlapping(values.as_ptr(), target, values.len());
        }
    }

    /// Writes the first `count` of a batch's `lanes` into column `col` from row `row` on: a
    /// whole batch (`count == 8`, every batch but a block's last) as one fixed-size store.
    ///
    /// A short batch's values are stored one by one with volatile writes: with a copy of
    /// run-time length in that branch, LLVM merged the two branches into one `memcpy` call per
    /// column, a call in the kernels' hot loops (seen with `perf`).
    #[inline(always)]
    pub(crate) fn write_lanes(&mut self, row: usize, col: usize, lanes: &[f64; 8], count: usize) {
        assert!(col < self.ncols && count <= 8 && row + count <= self.nrows);
        // SAFETY: in bounds (checked above) of memory the constructor's caller vouched for;
        // `write_unaligned` and `write_volatile` of f64s need no alignment beyond f64's.
        unsafe {
            let target = self.base.add(col * self.col_stride + row);
            if count == 8 {
                target.cast::<[f64; 8]>().write_unaligned(*lanes);
            } else {
                for (i, &value) in lanes[..count].iter().enumerate() {
                    target.add(i).write_volatile(value);
                }
            }
        }
    }
}
