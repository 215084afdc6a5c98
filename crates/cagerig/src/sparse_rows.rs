//! Generic sparse row-major matrices (CSR) acting on point sets, e.g. the CoR matrix S of Eq. 14
//! (`#V × #V`, CoRs = S·M) or loaded mesh-to-mesh weight files.

use glam::DVec3;
use rayon::prelude::*;

use crate::error::RigError;

/// Rows per rayon task in [`SparseRows::apply`].
const APPLY_GRAIN: usize = 2048;

/// A sparse `nrows × ncols` matrix in compressed-row storage.
///
/// Row `i` holds `cols[row_start[i]..row_start[i+1]]` (ascending, no duplicates) and the matching
/// `values`. `row_start.len() == nrows + 1`.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SparseRows {
    pub row_start: Vec<u32>,
    pub cols: Vec<u32>,
    pub values: Vec<f64>,
    pub ncols: usize,
}

impl SparseRows {
    /// Builds the matrix from `(row, col, value)` entries in any order; duplicates are summed,
    /// explicit zeros kept out. Indices out of range and non-finite values are rejected.
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
            if value != 0.0 {
                entries.push((row as u32, col as u32, value));
            }
        }
        entries.sort_by_key(|&(r, c, _)| (r, c));
        let mut row_start = vec![0u32; nrows + 1];
        let mut cols = Vec::with_capacity(entries.len());
        let mut values: Vec<f64> = Vec::with_capacity(entries.len());
        let mut last: Option<(u32, u32)> = None;
        for (r, c, v) in entries {
            if last == Some((r, c)) {
                if let Some(x) = values.last_mut() {
                    *x += v;
                }
                continue;
            }
            last = Some((r, c));
            row_start[r as usize + 1] += 1;
            cols.push(c);
            values.push(v);
        }
        for i in 0..nrows {
            row_start[i + 1] += row_start[i];
        }
        Ok(Self {
            row_start,
            cols,
            values,
            ncols,
        })
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
        let columns: Vec<Vec<f64>> = (0..num_cage)
            .into_par_iter()
            .map(|k| {
                let phi = cage_coords.column(k);
                (0..nrows)
                    .map(|i| {
                        let (cols, vals) = self.row(i);
                        cols.iter().zip(vals).map(|(&c, &v)| v * phi[c as usize]).sum()
                    })
                    .collect()
            })
            .collect();
        crate::cage_coords::CageCoords::from_matrix(faer::Mat::from_fn(nrows, num_cage, |i, k| {
            columns[k][i]
        }))
    }

    pub fn nrows(&self) -> usize {
        self.row_start.len().saturating_sub(1)
    }

    /// Number of stored non-zeros.
    pub fn nnz(&self) -> usize {
        self.values.len()
    }

    /// Columns and values of row `i`.
    #[inline]
    pub fn row(&self, i: usize) -> (&[u32], &[f64]) {
        let range = self.row_start[i] as usize..self.row_start[i + 1] as usize;
        (&self.cols[range.clone()], &self.values[range])
    }

    /// `out = self · points` (`out`: `nrows`, `points`: `ncols`), rayon-parallel, no allocation.
    ///
    /// # Panics
    /// If the slice lengths do not match the matrix shape.
    pub fn apply(&self, points: &[DVec3], out: &mut [DVec3]) {
        assert_eq!(points.len(), self.ncols, "SparseRows::apply: points");
        assert_eq!(out.len(), self.nrows(), "SparseRows::apply: out");
        out.par_chunks_mut(APPLY_GRAIN)
            .enumerate()
            .for_each(|(chunk, out_chunk)| {
                let first = chunk * APPLY_GRAIN;
                for (offset, o) in out_chunk.iter_mut().enumerate() {
                    let (cols, values) = self.row(first + offset);
                    *o = cols
                        .iter()
                        .zip(values)
                        .fold(DVec3::ZERO, |acc, (&c, &w)| acc + w * points[c as usize]);
                }
            });
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn triplets_sum_duplicates_and_apply() {
        let m = SparseRows::from_triplets(
            3,
            2,
            [
                (2, 1, 1.0),
                (0, 1, 0.25),
                (0, 0, 0.5),
                (0, 1, 0.25),
                (1, 0, 0.0),
            ],
        )
        .unwrap();
        assert_eq!(m.row(0), (&[0u32, 1][..], &[0.5, 0.5][..]));
        assert!(m.row(1).0.is_empty());
        assert_eq!(m.nnz(), 3);
        let mut out = vec![DVec3::ZERO; 3];
        m.apply(&[DVec3::X, DVec3::Y], &mut out);
        assert_eq!(out, vec![DVec3::new(0.5, 0.5, 0.0), DVec3::ZERO, DVec3::Y]);
        assert!(SparseRows::from_triplets(1, 1, [(0, 1, 1.0)]).is_err());
        assert!(SparseRows::from_triplets(1, 1, [(0, 0, f64::NAN)]).is_err());
    }
}
