//! The small dense products of the cage fits: a `#C × n` map (column-major, faer) times `n`
//! points, accumulated into `#C` points, column by column; and a map times a row-major table
//! ([`product_into`]). No allocation.

use faer::{Mat, MatRef};
use glam::DVec3;

/// `out += map · points` (`map` is `out.len() × points.len()`), column by column.
pub(crate) fn accumulate_product(map: &Mat<f64>, points: &[DVec3], out: &mut [DVec3]) {
    for (r, p) in points.iter().enumerate() {
        accumulate_column(map, r, *p, out);
    }
}

/// `out += map[:, r] · p`.
#[inline]
pub(crate) fn accumulate_column(map: &Mat<f64>, r: usize, p: DVec3, out: &mut [DVec3]) {
    let col = map.col(r);
    for (k, o) in out.iter_mut().enumerate() {
        *o += col[k] * p;
    }
}

/// `out` (`#rows × width`, row-major) = `left` (`#rows × n`) · `right` (`n × width`,
/// row-major), sequential: faer's product, or on the web target, where faer has no SIMD kernels
/// and runs its portable ones, [`tiled_product`] (the Fox's regularised CageRev, 100 × 200 ×
/// 900: 2.8–3.7 against 5.7–7.4 ms in V8, `docs/web.md`). The same up to round-off.
pub(crate) fn product_into(left: MatRef<'_, f64>, right: &[f64], width: usize, out: &mut [f64]) {
    #[cfg(not(target_arch = "wasm32"))]
    faer::linalg::matmul::matmul(
        faer::MatMut::from_row_major_slice_mut(out, left.nrows(), width),
        faer::Accum::Replace,
        left,
        MatRef::from_row_major_slice(right, left.ncols(), width),
        1.0,
        faer::Par::Seq,
    );
    #[cfg(target_arch = "wasm32")]
    tiled_product(left, right, width, out);
}

/// Rows of [`tiled_product`]'s tiles.
const TILE_ROWS: usize = 4;
/// Columns of [`tiled_product`]'s tiles.
const TILE_COLUMNS: usize = 4;

/// [`product_into`] by tiles of `TILE_ROWS × TILE_COLUMNS` outputs held in registers over the
/// whole inner dimension (each loaded entry of `right` serves `TILE_ROWS` outputs), which LLVM
/// vectorises with `simd128`; the edges one output at a time.
#[cfg_attr(not(any(target_arch = "wasm32", test)), expect(dead_code))]
fn tiled_product(left: MatRef<'_, f64>, right: &[f64], width: usize, out: &mut [f64]) {
    let (rows, inner) = (left.nrows(), left.ncols());
    debug_assert_eq!(right.len(), inner * width);
    debug_assert_eq!(out.len(), rows * width);
    let full_rows = rows - rows % TILE_ROWS;
    let full_columns = width - width % TILE_COLUMNS;
    for r0 in (0..full_rows).step_by(TILE_ROWS) {
        for c0 in (0..full_columns).step_by(TILE_COLUMNS) {
            let mut tile = [[0.0f64; TILE_COLUMNS]; TILE_ROWS];
            for k in 0..inner {
                let column = left.col(k);
                let start = k * width + c0;
                let entries = &right[start..start + TILE_COLUMNS];
                for (r, tile_row) in tile.iter_mut().enumerate() {
                    let a = column[r0 + r];
                    for (t, e) in tile_row.iter_mut().zip(entries) {
                        *t += a * *e;
                    }
                }
            }
            for (r, tile_row) in tile.iter().enumerate() {
                let start = (r0 + r) * width + c0;
                out[start..start + TILE_COLUMNS].copy_from_slice(tile_row);
            }
        }
    }
    // The edges: the last rows, and the last columns of the tiled rows.
    for r in 0..rows {
        let first_column = if r < full_rows { full_columns } else { 0 };
        for c in first_column..width {
            let mut sum = 0.0;
            for k in 0..inner {
                sum += left[(r, k)] * right[k * width + c];
            }
            out[r * width + c] = sum;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_random::uniform;

    /// The web target's tiled product equals faer's up to round-off, edges included.
    #[test]
    fn tiled_product_matches_faer() {
        let mut rng = uniform(3);
        for (rows, inner, width) in [(10, 13, 27), (8, 5, 8), (3, 4, 2), (1, 1, 1)] {
            let left = Mat::from_fn(rows, inner, |_, _| rng() - 0.5);
            let right: Vec<f64> = (0..inner * width).map(|_| rng() - 0.5).collect();
            let (mut tiled, mut reference) = (vec![0.0; rows * width], vec![0.0; rows * width]);
            tiled_product(left.as_ref(), &right, width, &mut tiled);
            faer::linalg::matmul::matmul(
                faer::MatMut::from_row_major_slice_mut(&mut reference, rows, width),
                faer::Accum::Replace,
                left.as_ref(),
                MatRef::from_row_major_slice(&right, inner, width),
                1.0,
                faer::Par::Seq,
            );
            let worst = tiled
                .iter()
                .zip(&reference)
                .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
            assert!(worst < 1e-14, "{rows} × {inner} × {width}: {worst:e}");
        }
    }
}
