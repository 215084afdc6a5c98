//! A generic sparse matrix in compressed-row storage, applied to point sets.
//!
//! Used for the CoR weights S (`#V × #V`, mesh-to-mesh: CoR_i = Σ_k S[i,k] · M_rest[k]) and any
//! other "each output point is a sparse combination of input points" operator.

use glam::DVec3;
use rayon::prelude::*;

use crate::error::RigError;

/// Rows per parallel task in [`SparseRows::apply`].
const ROW_BLOCK: usize = 1024;

/// Sparse `nrows × ncols` matrix, CSR: row `i` holds `cols[row_start[i]..row_start[i+1]]`
/// (ascending, no duplicates) and the matching `values`.
#[derive(Debug, Clone, PartialEq)]
pub struct SparseRows {
    row_start: Vec<u32>,
    cols: Vec<u32>,
    values: Vec<f64>,
    ncols: usize,
}

impl SparseRows {
    /// Builds the matrix from `(row, col, value)` entries in any order. Duplicates are summed;
    /// explicit zeros are kept. Indices out of range or non-finite values are rejected.
    pub fn from_triplets(
        nrows: usize,
        ncols: usize,
        triplets: impl IntoIterator<Item = (usize, usize, f64)>,
    ) -> Result<Self, RigError> {
        let mut entries: Vec<(u32, u32, f64)> = Vec::new();
        for (row, col, value) in triplets {
            if row >= nrows {
                return Err(RigError::IndexOutOfRange {
                    what: "sparse matrix row",
                    index: row,
                    len: nrows,
                });
            }
            if col >= ncols {
                return Err(RigError::IndexOutOfRange {
                    what: "sparse matrix column",
                    index: col,
                    len: ncols,
                });
            }
            if !value.is_finite() {
                return Err(RigError::NonFinite {
                    what: "sparse matrix row",
                    index: row,
                });
            }
            entries.push((row as u32, col as u32, value));
        }
        if nrows > u32::MAX as usize
            || ncols > u32::MAX as usize
            || entries.len() > u32::MAX as usize
        {
            return Err(RigError::Invalid(
                "sparse matrix too large for 32-bit indices".into(),
            ));
        }
        entries.sort_by_key(|&(r, c, _)| (r, c));
        let mut merged: Vec<(u32, u32, f64)> = Vec::with_capacity(entries.len());
        for e in entries {
            match merged.last_mut() {
                Some(last) if last.0 == e.0 && last.1 == e.1 => last.2 += e.2,
                _ => merged.push(e),
            }
        }
        let mut row_start = vec![0u32; nrows + 1];
        for &(r, _, _) in &merged {
            row_start[r as usize + 1] += 1;
        }
        for i in 0..nrows {
            row_start[i + 1] += row_start[i];
        }
        Ok(Self {
            row_start,
            cols: merged.iter().map(|e| e.1).collect(),
            values: merged.iter().map(|e| e.2).collect(),
            ncols,
        })
    }

    /// Wraps CSR arrays produced by the crate's own algorithms (rows ascending and in range by
    /// construction; checked in debug builds).
    pub(crate) fn from_csr_unchecked(
        row_start: Vec<u32>,
        cols: Vec<u32>,
        values: Vec<f64>,
        ncols: usize,
    ) -> Self {
        debug_assert_eq!(row_start.last().copied().unwrap_or(0) as usize, cols.len());
        debug_assert_eq!(cols.len(), values.len());
        debug_assert!(cols.iter().all(|&c| (c as usize) < ncols));
        Self {
            row_start,
            cols,
            values,
            ncols,
        }
    }

    /// The dense product `self · Φ` (`#rows × #C`) for a matrix whose columns address the rows
    /// of Φ: e.g. Λ = S·Φ of Eq. 14, so that CoRs = Λ·C. Parallel over the columns of Φ.
    pub fn compose_dense(
        &self,
        cage_coords: &crate::cage_coords::CageCoords,
    ) -> Result<crate::cage_coords::CageCoords, RigError> {
        if self.ncols != cage_coords.num_vertices() {
            return Err(RigError::SizeMismatch {
                what: "sparse matrix columns vs. rows of Φ",
                expected: cage_coords.num_vertices(),
                actual: self.ncols,
            });
        }
        let nrows = self.nrows();
        let num_cage = cage_coords.num_cage_vertices();
        // The columns, then the matrix: two copies of the result at the peak.
        crate::memory_estimate::check_table_allocation(
            "sparse rows × Φ",
            nrows.saturating_mul(2),
            "rows",
            num_cage,
        )?;
        let columns: Vec<Vec<f64>> = (0..num_cage)
            .into_par_iter()
            .map(|k| {
                let phi = cage_coords.column(k);
                (0..nrows)
                    .map(|i| {
                        let (cols, vals) = self.row(i);
                        cols.iter()
                            .zip(vals)
                            .map(|(&c, &v)| v * phi[c as usize])
                            .sum()
                    })
                    .collect()
            })
            .collect();
        crate::cage_coords::CageCoords::from_matrix(faer::Mat::from_fn(nrows, num_cage, |i, k| {
            columns[k][i]
        }))
    }

    /// Number of rows.
    pub fn nrows(&self) -> usize {
        self.row_start.len() - 1
    }

    /// Number of columns.
    pub fn ncols(&self) -> usize {
        self.ncols
    }

    /// Number of stored entries.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Columns and values of row `i` (ascending column).
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.row_start[i] as usize..self.row_start[i + 1] as usize;
        (&self.cols[range.clone()], &self.values[range])
    }

    /// Entry `(i, k)`, zero when not stored.
    pub fn get(&self, i: usize, k: usize) -> f64 {
        let (cols, values) = self.row(i);
        cols.binary_search(&(k as u32)).map_or(0.0, |p| values[p])
    }

    /// Raw CSR arrays `(row_start, cols, values)`.
    pub fn csr(&self) -> (&[u32], &[u32], &[f64]) {
        (&self.row_start, &self.cols, &self.values)
    }

    /// All entries `(row, col, value)` in row-major order.
    pub fn triplets(&self) -> impl Iterator<Item = (usize, usize, f64)> + '_ {
        (0..self.nrows()).flat_map(move |i| {
            let (cols, values) = self.row(i);
            cols.iter()
                .zip(values)
                .map(move |(&k, &w)| (i, k as usize, w))
        })
    }

    /// Sum of each row's values, `nrows`.
    pub fn row_sums(&self) -> Vec<f64> {
        (0..self.nrows())
            .map(|i| self.row(i).1.iter().sum())
            .collect()
    }

    /// `out_i = Σ_k w_ik · x_k` for every row: `x` is `ncols`, `out` is `nrows`.
    /// Parallel over row blocks, no allocation.
    pub fn apply(&self, x: &[DVec3], out: &mut [DVec3]) {
        assert_eq!(x.len(), self.ncols, "SparseRows::apply: input length");
        assert_eq!(out.len(), self.nrows(), "SparseRows::apply: output length");
        out.par_chunks_mut(ROW_BLOCK)
            .enumerate()
            .for_each(|(block, chunk)| {
                let first = block * ROW_BLOCK;
                for (offset, o) in chunk.iter_mut().enumerate() {
                    let (cols, values) = self.row(first + offset);
                    let mut sum = DVec3::ZERO;
                    for (&k, &w) in cols.iter().zip(values) {
                        sum += w * x[k as usize];
                    }
                    *o = sum;
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn builds_sorted_merged_rows_and_applies() {
        let s = SparseRows::from_triplets(
            3,
            4,
            [
                (0, 3, 0.5),
                (0, 1, 0.25),
                (2, 0, 1.0),
                (0, 1, 0.25),
                (1, 2, 0.0),
            ],
        )
        .unwrap();
        assert_eq!(s.row(0), (&[1u32, 3][..], &[0.5, 0.5][..]));
        assert_eq!(s.row(1).0, &[2]);
        assert_eq!(s.nnz(), 4);
        assert_eq!(s.get(2, 0), 1.0);
        assert_eq!(s.get(2, 1), 0.0);
        let x = [DVec3::X, DVec3::Y, DVec3::Z, DVec3::new(1.0, 1.0, 1.0)];
        let mut out = [DVec3::splat(9.0); 3];
        s.apply(&x, &mut out);
        assert_eq!(out[0], DVec3::new(0.5, 1.0, 0.5));
        assert_eq!(out[1], DVec3::ZERO);
        assert_eq!(out[2], DVec3::X);
        assert_eq!(s.row_sums(), vec![1.0, 0.0, 1.0]);
        let t: Vec<_> = s.triplets().collect();
        assert_eq!(SparseRows::from_triplets(3, 4, t).unwrap(), s);
    }

    #[test]
    fn apply_many_rows_in_parallel_matches_serial() {
        let n = 5000;
        let s = SparseRows::from_triplets(
            n,
            n,
            (0..n).flat_map(|i| [(i, i, 0.5), (i, (i * 7 + 3) % n, 0.5)]),
        )
        .unwrap();
        let x: Vec<DVec3> = (0..n)
            .map(|i| DVec3::new(i as f64, 1.0, -(i as f64)))
            .collect();
        let mut out = vec![DVec3::ZERO; n];
        s.apply(&x, &mut out);
        for i in [0, 1023, 1024, 4999] {
            assert_eq!(out[i], 0.5 * x[i] + 0.5 * x[(i * 7 + 3) % n]);
        }
    }

    #[test]
    fn rejects_bad_entries() {
        assert!(matches!(
            SparseRows::from_triplets(2, 2, [(2, 0, 1.0)]),
            Err(RigError::IndexOutOfRange { index: 2, .. })
        ));
        assert!(matches!(
            SparseRows::from_triplets(2, 2, [(0, 5, 1.0)]),
            Err(RigError::IndexOutOfRange { index: 5, .. })
        ));
        assert!(matches!(
            SparseRows::from_triplets(2, 2, [(1, 0, f64::INFINITY)]),
            Err(RigError::NonFinite { index: 1, .. })
        ));
    }
}
