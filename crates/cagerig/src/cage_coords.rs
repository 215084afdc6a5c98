//! Cage coordinates Φ (`#V × #C`, dense): mesh vertex i = Σ_k Φ[i,k] · cage vertex k (Eq. 7).
//!
//! Storage layout: **column-major** (`faer::Mat<f64>`), i.e. each cage vertex's column of `#V`
//! weights is contiguous. This serves the three later uses:
//! - M = ΦC for all vertices streams each column once (`apply`, vectorisable, split by row blocks
//!   across threads);
//! - an edit of k cage vertices updates M by Φ[:, k] · ΔC_k, reading just k contiguous columns
//!   (`apply_delta`, O(#V·k));
//! - MaxVol / CageUp gather a few rows once at precomputation time (`select_rows`), where the
//!   strided access does not matter.

use faer::Mat;
use glam::DVec3;
use rayon::prelude::*;

use crate::error::RigError;

/// Rows per parallel task in the per-frame products.
const ROW_BLOCK: usize = 4096;

/// Cage coordinates Φ, `#V × #C`, column-major.
#[derive(Debug, Clone, PartialEq)]
pub struct CageCoords {
    matrix: Mat<f64>,
}

impl CageCoords {
    /// Wraps a `#V × #C` matrix, checking every entry is finite.
    pub fn from_matrix(matrix: Mat<f64>) -> Result<Self, RigError> {
        for k in 0..matrix.ncols() {
            let col = matrix.col(k);
            for i in 0..matrix.nrows() {
                if !col[i].is_finite() {
                    return Err(RigError::NonFinite {
                        what: "cage coordinate row",
                        index: i,
                    });
                }
            }
        }
        Ok(Self { matrix })
    }

    /// Wraps a `#V × #C` matrix whose entries the caller has already checked to be finite.
    pub(crate) fn from_checked_matrix(matrix: Mat<f64>) -> Self {
        debug_assert!((0..matrix.ncols()).all(|k| matrix.col(k).iter().all(|v| v.is_finite())));
        Self { matrix }
    }

    /// Builds Φ from `#V` rows of `#C` weights each.
    pub fn from_rows(rows: &[Vec<f64>], num_cage_vertices: usize) -> Result<Self, RigError> {
        for r in rows {
            if r.len() != num_cage_vertices {
                return Err(RigError::SizeMismatch {
                    what: "cage coordinate row length",
                    expected: num_cage_vertices,
                    actual: r.len(),
                });
            }
        }
        Self::from_matrix(Mat::from_fn(rows.len(), num_cage_vertices, |i, k| {
            rows[i][k]
        }))
    }

    pub fn num_vertices(&self) -> usize {
        self.matrix.nrows()
    }

    pub fn num_cage_vertices(&self) -> usize {
        self.matrix.ncols()
    }

    pub fn matrix(&self) -> &Mat<f64> {
        &self.matrix
    }

    /// Φ[i, k].
    #[inline]
    pub fn get(&self, i: usize, k: usize) -> f64 {
        self.matrix[(i, k)]
    }

    /// Column k (the weights of cage vertex k on every mesh vertex), contiguous, `#V`.
    #[inline]
    pub fn column(&self, k: usize) -> &[f64] {
        let col = self.matrix.col(k);
        // SAFETY-free path: faer columns of an owned Mat are contiguous.
        col.try_as_col_major().map(|c| c.as_slice()).unwrap_or(&[])
    }

    /// Copies row i into `out` (`#C`).
    pub fn row_into(&self, i: usize, out: &mut [f64]) {
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.matrix[(i, k)];
        }
    }

    /// The `rows.len() × #C` submatrix Φ̃ of the given rows.
    pub fn select_rows(&self, rows: &[usize]) -> Mat<f64> {
        Mat::from_fn(rows.len(), self.num_cage_vertices(), |r, k| {
            self.matrix[(rows[r], k)]
        })
    }

    /// M = Φ·C (Eq. 7): `cage` is `#C`, `out` is `#V`. Parallel over row blocks, no allocation.
    pub fn apply(&self, cage: &[DVec3], out: &mut [DVec3]) {
        debug_assert_eq!(cage.len(), self.num_cage_vertices());
        debug_assert_eq!(out.len(), self.num_vertices());
        out.par_chunks_mut(ROW_BLOCK)
            .enumerate()
            .for_each(|(block, chunk)| {
                let start = block * ROW_BLOCK;
                chunk.iter_mut().for_each(|o| *o = DVec3::ZERO);
                for (k, c) in cage.iter().enumerate() {
                    let col = &self.column(k)[start..start + chunk.len()];
                    for (o, &w) in chunk.iter_mut().zip(col) {
                        *o += w * *c;
                    }
                }
            });
    }

    /// M += Φ[:, k]·ΔC_k for the edited cage vertices only: O(#V · k). No allocation.
    pub fn apply_delta(&self, cage_vertices: &[usize], deltas: &[DVec3], out: &mut [DVec3]) {
        debug_assert_eq!(cage_vertices.len(), deltas.len());
        out.par_chunks_mut(ROW_BLOCK)
            .enumerate()
            .for_each(|(block, chunk)| {
                let start = block * ROW_BLOCK;
                for (&k, d) in cage_vertices.iter().zip(deltas) {
                    let col = &self.column(k)[start..start + chunk.len()];
                    for (o, &w) in chunk.iter_mut().zip(col) {
                        *o += w * *d;
                    }
                }
            });
    }

    /// Largest |Σ_k Φ[i,k] − 1| over rows (partition-of-unity residual).
    pub fn max_partition_error(&self) -> f64 {
        (0..self.num_vertices())
            .map(|i| {
                let s: f64 = (0..self.num_cage_vertices())
                    .map(|k| self.matrix[(i, k)])
                    .sum();
                (s - 1.0).abs()
            })
            .fold(0.0, f64::max)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn apply_and_delta_agree() {
        let rows: Vec<Vec<f64>> = (0..10_000)
            .map(|i| {
                let a = (i % 7) as f64 / 7.0;
                vec![a, 0.5 - a / 2.0, 0.5 - a / 2.0]
            })
            .collect();
        let phi = CageCoords::from_rows(&rows, 3).unwrap();
        let cage = vec![DVec3::X, DVec3::Y, DVec3::new(1.0, 2.0, 3.0)];
        let mut m = vec![DVec3::ZERO; rows.len()];
        phi.apply(&cage, &mut m);
        let i = 5000;
        let expect = rows[i][0] * cage[0] + rows[i][1] * cage[1] + rows[i][2] * cage[2];
        assert!(m[i].abs_diff_eq(expect, 1e-15));
        let mut moved = cage.clone();
        moved[2] += DVec3::new(0.5, -1.0, 2.0);
        phi.apply_delta(&[2], &[DVec3::new(0.5, -1.0, 2.0)], &mut m);
        let mut full = vec![DVec3::ZERO; rows.len()];
        phi.apply(&moved, &mut full);
        assert!(crate::mesh::max_distance(&m, &full) < 1e-14);
        assert!(matches!(
            CageCoords::from_rows(&[vec![1.0]], 2),
            Err(RigError::SizeMismatch { .. })
        ));
    }
}
