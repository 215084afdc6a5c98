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

mod column_products;
mod display_coords;

use faer::Mat;
use glam::DVec3;

pub use display_coords::DisplayCageCoords;

use crate::error::RigError;
#[cfg(test)]
use column_products::{LANE_BLOCK, ROW_BLOCK};
use column_products::{
    OffsetTerms, ScatteredTerms, accumulate_columns, accumulate_columns_then, call_on_tiles,
    rows_of_columns,
};

/// How the per-frame products M = ΦC and M += Φ[:, k]·ΔC_k read Φ.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum CoordsPrecision {
    /// Φ as computed, read as f64 (the exact path: tests compare with the paper tool at 1e-9).
    #[default]
    F64,
    /// Φ rounded once to the nearest f32 values ([`CageCoords::round_to_f32`]): the products read
    /// half the bytes and still accumulate in f64. Every invariant (M = ΦC, the CageUp/CageRev
    /// loop) holds to f64 round-off for the rounded Φ; the coordinates themselves move by at
    /// most 2⁻²⁴ relative, so ΦC departs from the input rest mesh by ~1e-7 of its size.
    F32,
}

impl CoordsPrecision {
    /// Every precision, the default first.
    pub const ALL: [CoordsPrecision; 2] = [Self::F64, Self::F32];

    /// The name front ends use (`--coords-precision`, Python's `coords_precision=`; serde's too).
    pub const fn name(self) -> &'static str {
        match self {
            Self::F64 => "f64",
            Self::F32 => "f32",
        }
    }

    /// One line for `--help`.
    pub const fn help(self) -> &'static str {
        match self {
            Self::F64 => "Φ as computed (exact; matches the paper tool's outputs to 1e-9)",
            Self::F32 => {
                "Φ rounded to f32 once: half the memory traffic per frame, invariants still exact \
                 for the rounded Φ, rest mesh moved by ~1e-7 of its size"
            }
        }
    }
}

/// A name that is not a [`CoordsPrecision`].
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
#[error(
    "unknown coordinates precision {found:?}: expected {}",
    CoordsPrecision::names_text()
)]
pub struct UnknownCoordsPrecision {
    /// The name given.
    pub found: String,
}

crate::named_kind::named_kind!(
    CoordsPrecision,
    UnknownCoordsPrecision,
    CoordsPrecision::help,
    no_serde
);

/// Cage coordinates Φ, `#V × #C`, column-major.
#[derive(Debug, Clone, PartialEq)]
pub struct CageCoords {
    matrix: Mat<f64>,
    /// After [`CageCoords::round_to_f32`]: the same (rounded) Φ as f32, column-major with
    /// stride `#V`, which the per-frame products read instead of `matrix`.
    compact: Option<Vec<f32>>,
}

impl CageCoords {
    /// Wraps a `#V × #C` matrix, checking every entry is finite and at most
    /// [`crate::error::MAX_INPUT_MAGNITUDE`] in magnitude.
    pub fn from_matrix(matrix: Mat<f64>) -> Result<Self, RigError> {
        for k in 0..matrix.ncols() {
            let col = matrix.col(k);
            for i in 0..matrix.nrows() {
                if !crate::error::is_input_value(col[i]) {
                    return Err(RigError::ValueOutOfBounds {
                        what: "cage coordinate row",
                        index: i,
                        value: col[i],
                    });
                }
            }
        }
        Ok(Self {
            matrix,
            compact: None,
        })
    }

    /// Wraps a `#V × #C` matrix whose entries the caller has already checked to be finite.
    pub(crate) fn from_checked_matrix(matrix: Mat<f64>) -> Self {
        debug_assert!((0..matrix.ncols()).all(|k| matrix.col(k).iter().all(|v| v.is_finite())));
        Self {
            matrix,
            compact: None,
        }
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

    /// Number of mesh vertices `#V` (rows of Φ).
    pub fn num_vertices(&self) -> usize {
        self.matrix.nrows()
    }

    /// Number of cage vertices `#C` (columns of Φ).
    pub fn num_cage_vertices(&self) -> usize {
        self.matrix.ncols()
    }

    /// Φ as a dense `#V × #C` matrix.
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

    /// Rounds every entry of Φ to the nearest f32 and keeps an f32 copy that [`Self::apply`] and
    /// [`Self::apply_delta`] read from then on (half the memory traffic; sums stay f64, and give
    /// the same numbers as the f64 path on the rounded Φ). Idempotent.
    pub fn round_to_f32(&mut self) {
        let (nv, nc) = (self.num_vertices(), self.num_cage_vertices());
        let mut compact = Vec::with_capacity(nv * nc);
        for k in 0..nc {
            let mut col = self.matrix.col_mut(k);
            for i in 0..nv {
                let rounded = col[i] as f32;
                col[i] = f64::from(rounded);
                compact.push(rounded);
            }
        }
        self.compact = Some(compact);
    }

    /// The precision the per-frame products read Φ in.
    pub fn precision(&self) -> CoordsPrecision {
        if self.compact.is_some() {
            CoordsPrecision::F32
        } else {
            CoordsPrecision::F64
        }
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
        self.accumulate(&[OffsetTerms::new(0, cage)], false, out);
    }

    /// M = Φ·C + Ψ·g in one pass over the rows, for coordinates `extra` = Ψ (`#V × #F`) whose
    /// column f multiplies `extra_terms[f]` (`#F`): the Green rest skin φC + ψ·g(C) (G1). The
    /// same bits as [`Self::apply`] followed by `extra.apply_delta` over every column of Ψ in
    /// order, without writing M and reading it back between the two (at 133k × (58 + 112) that
    /// is a second pass over the output and its tiles). Parallel over row blocks, no
    /// allocation.
    pub fn apply_with_extra(
        &self,
        cage: &[DVec3],
        extra: &CageCoords,
        extra_terms: &[DVec3],
        out: &mut [DVec3],
    ) {
        // A second output of zero-sized points: no allocation.
        let mut no_second = vec![(); out.len()];
        self.apply_then(
            cage,
            Some((extra, extra_terms)),
            out,
            &mut no_second,
            |_, _, _| {},
        );
    }

    /// M = Φ·C [+ Ψ·g] as [`Self::apply`] / [`Self::apply_with_extra`] (the same bits), calling
    /// `then(first_row, rows_of_m, rows_of_second)` from the thread that computed them on each
    /// finished tile of M (a few thousand rows, still in the core's cache) with the same rows
    /// of `second` (`#V`; of zero-sized points where there is none): the rest skin and its
    /// skinning in one pass (`RigSession`'s exact path under LBS).
    ///
    /// # Panics
    /// If `second` is not `#V` long.
    pub fn apply_then<Q: Send>(
        &self,
        cage: &[DVec3],
        extra: Option<(&CageCoords, &[DVec3])>,
        out: &mut [DVec3],
        second: &mut [Q],
        then: impl Fn(usize, &[DVec3], &mut [Q]) + Send + Sync,
    ) {
        let nc = self.num_cage_vertices();
        let nv = self.num_vertices();
        debug_assert_eq!(cage.len(), nc);
        debug_assert_eq!(out.len(), nv);
        let (extra, extra_terms) = match extra {
            Some((extra, terms)) => (Some(extra), terms),
            None => (None, &[][..]),
        };
        debug_assert!(
            extra.is_none_or(
                |e| e.num_vertices() == nv && e.num_cage_vertices() == extra_terms.len()
            )
        );
        let parts = [OffsetTerms::new(0, cage), OffsetTerms::new(nc, extra_terms)];
        self.accumulate_with_extra_then(extra, &parts, false, out, second, then);
    }

    /// out (`#V`) += Φ[:, cage_vertices]·deltas + Ψ[:, extra_columns]·extra_deltas, Ψ =
    /// `extra` (`#V × #F`), in one pass over the rows: the bits of [`Self::apply_delta`]
    /// followed by `extra.apply_delta`, reading and writing `out` once instead of twice (a
    /// Green rest-cage drag: the moved vertices' columns of φ, then their faces' of ψ); nothing
    /// when there is no column. Parallel over row blocks, no allocation.
    pub fn apply_delta_with_extra(
        &self,
        cage_vertices: &[usize],
        deltas: &[DVec3],
        extra: &CageCoords,
        extra_columns: &[usize],
        extra_deltas: &[DVec3],
        out: &mut [DVec3],
    ) {
        debug_assert_eq!(cage_vertices.len(), deltas.len());
        debug_assert_eq!(extra_columns.len(), extra_deltas.len());
        debug_assert_eq!(extra.num_vertices(), self.num_vertices());
        if cage_vertices.is_empty() && extra_columns.is_empty() {
            return;
        }
        let parts = [
            ScatteredTerms::new(0, cage_vertices, deltas),
            ScatteredTerms::new(self.num_cage_vertices(), extra_columns, extra_deltas),
        ];
        let mut no_second = vec![(); out.len()];
        self.accumulate_with_extra_then(
            Some(extra),
            &parts,
            true,
            out,
            &mut no_second,
            |_, _, _| {},
        );
    }

    /// `out = [out +] Σ` over the terms of `parts`, whose columns k < #C are Φ's and
    /// #C + f are column f of `extra` (Ψ, `#V × #F`), in one pass over the rows (two where Φ
    /// and Ψ are stored in different precisions), calling `then` on each finished tile as
    /// [`Self::apply_then`].
    fn accumulate_with_extra_then<I, Q: Send>(
        &self,
        extra: Option<&CageCoords>,
        parts: &[I; 2],
        add_to_out: bool,
        out: &mut [DVec3],
        second: &mut [Q],
        then: impl Fn(usize, &[DVec3], &mut [Q]) + Send + Sync,
    ) where
        I: Iterator<Item = (usize, DVec3)> + Clone + Send + Sync,
    {
        let (nc, nv) = (self.num_cage_vertices(), self.num_vertices());
        if extra.is_some_and(|e| e.compact.is_some() != self.compact.is_some()) {
            // Φ and Ψ stored in different precisions: the two products one after the other.
            self.accumulate(&parts[..1], add_to_out, out);
            if let Some(extra) = extra {
                let own_columns = parts[1].clone().map(move |(k, d)| (k - nc, d));
                extra.accumulate(&[own_columns], true, out);
            }
            call_on_tiles(out, second, then);
            return;
        }
        match &self.compact {
            None => {
                let column = |k: usize| match (k.checked_sub(nc), extra) {
                    (Some(f), Some(extra)) => extra.column(f),
                    (None, _) | (Some(_), None) => self.column(k),
                };
                accumulate_columns_then(column, parts, add_to_out, out, second, then);
            }
            Some(compact) => {
                let extra_compact = extra.and_then(|e| e.compact.as_deref()).unwrap_or(&[]);
                let column = |k: usize| match k.checked_sub(nc) {
                    Some(f) => &extra_compact[f * nv..(f + 1) * nv],
                    None => &compact[k * nv..(k + 1) * nv],
                };
                accumulate_columns_then(column, parts, add_to_out, out, second, then);
            }
        }
    }

    /// M += Φ[:, k]·ΔC_k for the edited cage vertices only: O(#V · k), and nothing at all
    /// (not a pass over M) when there is none. No allocation.
    pub fn apply_delta(&self, cage_vertices: &[usize], deltas: &[DVec3], out: &mut [DVec3]) {
        debug_assert_eq!(cage_vertices.len(), deltas.len());
        if cage_vertices.is_empty() {
            return;
        }
        self.accumulate(
            &[cage_vertices.iter().copied().zip(deltas.iter().copied())],
            true,
            out,
        );
    }

    /// The rows `rows` of Φ as coordinates of their own (`rows.len() × #C`, kept in the same
    /// precision), so that products over those rows read a few contiguous kilobytes instead of
    /// one scattered entry per column: `selected.apply_rows(&[0, 1, ..], ..)` gives the same bits
    /// as `self.apply_rows(rows, ..)`.
    pub fn rows_as_coords(&self, rows: &[usize]) -> CageCoords {
        let matrix = self.select_rows(rows);
        let nv = self.num_vertices();
        let compact = self.compact.as_ref().map(|compact| {
            (0..self.num_cage_vertices())
                .flat_map(|k| rows.iter().map(move |&r| compact[k * nv + r]))
                .collect()
        });
        CageCoords { matrix, compact }
    }

    /// Rows `rows` of M = Φ·C into `out` (`rows.len()`): the same bits as those rows of
    /// [`Self::apply`], in O(#rows · #C). The display path keeps the exact M on CageUp's MaxVol
    /// rows with it.
    pub fn apply_rows(&self, rows: &[usize], cage: &[DVec3], out: &mut [DVec3]) {
        debug_assert_eq!(cage.len(), self.num_cage_vertices());
        self.rows(rows, cage, false, out);
    }

    /// Rows `rows` of M += Φ·D into `out` (`rows.len()`, holding those rows of M) for one
    /// `d_k` per column (`D`, `#C`): the same bits as those rows of
    /// [`Self::apply_delta`] over every column in order. The Green display path keeps the exact
    /// face terms ψ·g on CageUp's rows with it.
    pub fn add_rows(&self, rows: &[usize], deltas: &[DVec3], out: &mut [DVec3]) {
        debug_assert_eq!(deltas.len(), self.num_cage_vertices());
        self.rows(rows, deltas, true, out);
    }

    /// [`Self::apply_rows`] / [`Self::add_rows`].
    fn rows(&self, rows: &[usize], cage: &[DVec3], add_to_out: bool, out: &mut [DVec3]) {
        let terms = cage.iter().enumerate().map(|(k, c)| (k, *c));
        match &self.compact {
            Some(compact) => {
                let nv = self.num_vertices();
                rows_of_columns(
                    &|k| &compact[k * nv..(k + 1) * nv],
                    terms,
                    add_to_out,
                    rows,
                    out,
                )
            }
            None => rows_of_columns(&|k| self.column(k), terms, add_to_out, rows, out),
        }
    }

    /// `out = [out +] Σ Φ[:, k]·d_k` over the terms (k, d_k) of every part in turn (each grouped
    /// on its own, the sums carrying over), `out` being `#V`.
    ///
    /// Each thread takes [`column_products::ROW_BLOCK`] rows and splits them into
    /// [`column_products::LANE_BLOCK`]-row tiles whose x, y and z sums live in three
    /// structure-of-arrays accumulators (in L1/L2), so the inner loop is vectorised fused
    /// multiply-adds over rows (the arithmetic: `column_products`); columns are taken eight per
    /// pass over the sums (an eighth of the accumulator traffic). Eight columns per pass
    /// instead of four took the f64 product at 532k × 58 from 7.4 to ≈ 6 ms on an earlier
    /// machine; the point-by-point `DVec3` loop took 7.3 ms at 133k × 58. On today's 2-core
    /// host each core reads about 15 GB/s (one thread takes twice as long as two): the product
    /// is bound by the memory accesses each core keeps in flight.
    fn accumulate<I>(&self, parts: &[I], add_to_out: bool, out: &mut [DVec3])
    where
        I: Iterator<Item = (usize, DVec3)> + Clone + Send + Sync,
    {
        match &self.compact {
            Some(compact) => {
                let nv = self.num_vertices();
                accumulate_columns(|k| &compact[k * nv..(k + 1) * nv], parts, add_to_out, out)
            }
            None => accumulate_columns(|k| self.column(k), parts, add_to_out, out),
        }
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
mod tests;
