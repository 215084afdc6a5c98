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
    OffsetTerms, accumulate_columns, accumulate_columns_then, call_on_tiles, rows_of_columns,
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
        if extra.is_some_and(|e| e.compact.is_some() != self.compact.is_some()) {
            // Φ and Ψ stored in different precisions: the two products one after the other.
            self.accumulate(&parts[..1], false, out);
            if let Some(extra) = extra {
                extra.accumulate(&[OffsetTerms::new(0, extra_terms)], true, out);
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
                accumulate_columns_then(column, &parts, false, out, second, then);
            }
            Some(compact) => {
                let extra_compact = extra.and_then(|e| e.compact.as_deref()).unwrap_or(&[]);
                let column = |k: usize| match k.checked_sub(nc) {
                    Some(f) => &extra_compact[f * nv..(f + 1) * nv],
                    None => &compact[k * nv..(k + 1) * nv],
                };
                accumulate_columns_then(column, &parts, false, out, second, then);
            }
        }
    }

    /// M += Φ[:, k]·ΔC_k for the edited cage vertices only: O(#V · k). No allocation.
    pub fn apply_delta(&self, cage_vertices: &[usize], deltas: &[DVec3], out: &mut [DVec3]) {
        debug_assert_eq!(cage_vertices.len(), deltas.len());
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
mod tests {
    use super::*;

    #[test]
    fn f32_storage_gives_the_f64_products_of_the_rounded_coordinates() {
        let (nv, nc) = (1500, 7);
        let matrix = Mat::from_fn(nv, nc, |i, k| {
            ((i * 31 + k * 17) % 101) as f64 / 707.0 + 1e-9
        });
        let mut rounded = CageCoords::from_matrix(matrix.clone()).unwrap();
        rounded.round_to_f32();
        assert_eq!(rounded.precision(), CoordsPrecision::F32);
        // Entries moved by at most half an f32 ulp.
        for k in 0..nc {
            for i in 0..nv {
                let (a, b) = (matrix[(i, k)], rounded.get(i, k));
                assert!((a - b).abs() <= a.abs() * 2f64.powi(-24));
            }
        }
        // The f64 path on the rounded values and the f32 path agree bit for bit.
        let f64_path = CageCoords::from_matrix(rounded.matrix().clone()).unwrap();
        assert_eq!(f64_path.precision(), CoordsPrecision::F64);
        let cage: Vec<DVec3> = (0..nc)
            .map(|k| DVec3::new(k as f64 * 0.3, 1.0 - k as f64, 0.25 * (k * k) as f64))
            .collect();
        let (mut a, mut b) = (vec![DVec3::ZERO; nv], vec![DVec3::ZERO; nv]);
        rounded.apply(&cage, &mut a);
        f64_path.apply(&cage, &mut b);
        assert_eq!(a, b);
        let (vertices, deltas) = (
            [5usize, 0, 3],
            [DVec3::X, DVec3::new(0.1, -2.0, 3.0), DVec3::Z],
        );
        rounded.apply_delta(&vertices, &deltas, &mut a);
        f64_path.apply_delta(&vertices, &deltas, &mut b);
        assert_eq!(a, b);
        // Rounding twice changes nothing.
        let again = rounded.clone();
        rounded.round_to_f32();
        assert_eq!(rounded, again);
    }

    #[test]
    fn apply_matches_the_plain_product_for_any_number_of_columns() {
        // Tiles of LANE_BLOCK rows, eight- and four-column groups and remainders: 1..=17
        // columns, odd #V.
        for nc in 1..=17 {
            let nv = 2 * ROW_BLOCK + LANE_BLOCK + 3;
            let matrix = Mat::from_fn(nv, nc, |i, k| ((i * 7 + k * 13) % 23) as f64 - 11.0);
            let phi = CageCoords::from_matrix(matrix.clone()).unwrap();
            let cage: Vec<DVec3> = (0..nc)
                .map(|k| DVec3::new(k as f64 + 1.0, 2.0 - k as f64, 0.5))
                .collect();
            let mut out = vec![DVec3::splat(99.0); nv];
            phi.apply(&cage, &mut out);
            for (i, o) in out.iter().enumerate() {
                let expected = (0..nc).fold(DVec3::ZERO, |acc, k| acc + matrix[(i, k)] * cage[k]);
                // Small integers times small integers: exact in any summation order.
                assert_eq!(*o, expected, "row {i}, {nc} columns");
            }
        }
    }

    /// `s + Σ_c w_c d_c` over one group as the products add it: the group's own chain of fused
    /// multiply-adds from `w₀·d₀`, added to `s`.
    fn group_reference(s: f64, w: &[f64], d: &[f64]) -> f64 {
        let t = (1..w.len()).fold(w[0] * d[0], |t, c| w[c].mul_add(d[c], t));
        s + t
    }

    #[test]
    fn every_product_adds_its_groups_as_fused_chains_in_column_order() {
        // The expected values come from `mul_add` in this test's baseline code (libm's
        // correctly rounded fma); `apply` runs the widest tier this CPU has and `apply_rows` its
        // own dispatch: the same bits prove every tier and both products add the groups of
        // eight, four and one columns (13 = 8 + 4 + 1) in order as `group_reference`; f64 and
        // f32 storage.
        let (nv, nc) = (LANE_BLOCK + 77, 13);
        let mut phi = varied(nv, nc, 5);
        let cage: Vec<DVec3> = (0..nc)
            .map(|k| {
                DVec3::new(
                    0.1 * k as f64 + 0.37,
                    1.3 - k as f64 / 7.0,
                    2.9 / (k + 1) as f64,
                )
            })
            .collect();
        for round in [false, true] {
            if round {
                phi.round_to_f32();
            }
            let expected: Vec<DVec3> = (0..nv)
                .map(|i| {
                    let mut s = [0.0; 3];
                    for group in [0..8, 8..12, 12..13] {
                        let w: Vec<f64> = group.clone().map(|k| phi.get(i, k)).collect();
                        for (a, sum) in s.iter_mut().enumerate() {
                            let d: Vec<f64> = group.clone().map(|k| cage[k][a]).collect();
                            *sum = group_reference(*sum, &w, &d);
                        }
                    }
                    DVec3::from_array(s)
                })
                .collect();
            let mut out = vec![DVec3::NAN; nv];
            phi.apply(&cage, &mut out);
            assert_eq!(out, expected, "f32 storage {round}");
            let rows = [0, 5, LANE_BLOCK, nv - 1];
            let mut picked = vec![DVec3::NAN; rows.len()];
            phi.apply_rows(&rows, &cage, &mut picked);
            for (r, &row) in rows.iter().enumerate() {
                assert_eq!(picked[r], expected[row], "row {row}, f32 storage {round}");
            }
        }
    }

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

    #[test]
    fn apply_rows_gives_the_bits_of_apply() {
        // Column counts with and without a group of four or single columns after the groups of
        // eight (58: the Arm's cage, 7 × 8 + 2).
        for nc in [3, 4, 7, 8, 9, 13, 15, 58] {
            let nv = 9000;
            let matrix = Mat::from_fn(nv, nc, |i, k| {
                (((i * 7919 + k * 104_729) % 1013) as f64 / 1013.0 - 0.3) * 1.1f64.powi(k as i32)
            });
            let mut phi = CageCoords::from_matrix(matrix).unwrap();
            let cage: Vec<DVec3> = (0..nc)
                .map(|k| DVec3::new(0.1 * k as f64 + 0.37, 1.3 - k as f64 / 7.0, 2.9))
                .collect();
            for round in [false, true] {
                if round {
                    phi.round_to_f32();
                }
                let mut full = vec![DVec3::ZERO; nv];
                phi.apply(&cage, &mut full);
                let rows = [0, 1, 511, 512, 4095, 4096, 8999, 17];
                let mut picked = vec![DVec3::NAN; rows.len()];
                phi.apply_rows(&rows, &cage, &mut picked);
                for (r, &row) in rows.iter().enumerate() {
                    assert_eq!(picked[r], full[row], "{nc} columns, row {row}, f32 {round}");
                }
                // The rows selected as coordinates of their own: the same bits again, and
                // add_rows on top of them as on the full coordinates.
                let selected = phi.rows_as_coords(&rows);
                let identity: Vec<usize> = (0..rows.len()).collect();
                let mut from_selected = vec![DVec3::NAN; rows.len()];
                selected.apply_rows(&identity, &cage, &mut from_selected);
                assert_eq!(from_selected, picked, "{nc} columns, f32 {round}");
                phi.add_rows(&rows, &cage, &mut picked);
                selected.add_rows(&identity, &cage, &mut from_selected);
                assert_eq!(from_selected, picked, "{nc} columns, f32 {round}");
            }
        }
    }

    /// A test matrix whose entries differ from column to column and row to row.
    fn varied(nv: usize, nc: usize, seed: usize) -> CageCoords {
        CageCoords::from_matrix(Mat::from_fn(nv, nc, |i, k| {
            (((i * 7919 + k * 104_729 + seed * 31) % 1013) as f64 / 1013.0 - 0.3)
                * 1.07f64.powi(k as i32)
        }))
        .unwrap()
    }

    #[test]
    fn the_one_pass_product_with_extra_columns_gives_the_bits_of_two_passes() {
        // Φ with a partial group at its end (58 = 7 × 8 + 2) and Ψ of 112 and 5 columns, over
        // a row count that ends in a partial tile and a partial row block; each of Φ and Ψ in
        // f64 or rounded to f32 (the mixed cases take the two passes).
        let nv = 2 * ROW_BLOCK + LANE_BLOCK + 37;
        for (nc, nf) in [(58, 112), (9, 5)] {
            for (round_phi, round_psi) in
                [(false, false), (true, true), (true, false), (false, true)]
            {
                let mut phi = varied(nv, nc, 1);
                let mut psi = varied(nv, nf, 2);
                if round_phi {
                    phi.round_to_f32();
                }
                if round_psi {
                    psi.round_to_f32();
                }
                let cage: Vec<DVec3> = (0..nc)
                    .map(|k| DVec3::new(0.1 * k as f64 + 0.37, 1.3 - k as f64 / 7.0, 2.9))
                    .collect();
                let terms: Vec<DVec3> = (0..nf)
                    .map(|f| DVec3::new(-0.2 * f as f64, 0.03 * f as f64 + 1.0, 0.7))
                    .collect();
                let mut two_passes = vec![DVec3::ZERO; nv];
                phi.apply(&cage, &mut two_passes);
                let all: Vec<usize> = (0..nf).collect();
                psi.apply_delta(&all, &terms, &mut two_passes);
                let mut one_pass = vec![DVec3::NAN; nv];
                phi.apply_with_extra(&cage, &psi, &terms, &mut one_pass);
                let case = format!("{nc} + {nf} columns, f32 {round_phi}/{round_psi}");
                assert_eq!(one_pass, two_passes, "{case}");
                // The tiles handed on: every row once, holding its final value.
                let mut seen = vec![DVec3::NAN; nv];
                let mut again = vec![DVec3::NAN; nv];
                phi.apply_then(
                    &cage,
                    Some((&psi, &terms)),
                    &mut again,
                    &mut seen,
                    |first, rows, copy| {
                        assert!(rows.len() <= LANE_BLOCK && first % LANE_BLOCK == 0);
                        assert!(copy.iter().all(|p| p.is_nan()), "{first}: a row twice");
                        copy.copy_from_slice(rows);
                    },
                );
                assert_eq!(again, two_passes, "{case}");
                assert_eq!(seen, two_passes, "{case}");
            }
        }
        // Without extra columns: the bits of apply.
        let phi = varied(nv, 58, 3);
        let cage = vec![DVec3::new(1.0, -2.0, 0.5); 58];
        let mut plain = vec![DVec3::ZERO; nv];
        phi.apply(&cage, &mut plain);
        let (mut out, mut seen) = (vec![DVec3::NAN; nv], vec![DVec3::NAN; nv]);
        phi.apply_then(&cage, None, &mut out, &mut seen, |_, rows, copy| {
            copy.copy_from_slice(rows)
        });
        assert_eq!((&out, &seen), (&plain, &plain));
    }
}
