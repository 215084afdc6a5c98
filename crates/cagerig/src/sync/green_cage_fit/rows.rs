//! The fitting rows of a Green cage map, `F_R(x) = φ_R x + ψ_R g(x)`, and their Jacobian: shared
//! by CageUp's fit ([`super::GreenCageFit`]), CageRev ([`super::reverser`])
//! and SkelUp's joints (the same form with Ψ_φ, Ψ_ψ).

use faer::Mat;
use glam::DVec3;

use crate::coords::stretched_normals::StretchedNormals;

/// The Jacobian of rows `φ x + ψ g(x)` (`vertex_rows` φ `#R × #C`, `face_rows` ψ `#R × #F`) at
/// x (`#C`): `φ ⊗ I₃ + ψ ∂g/∂x` into `out` (`3#R × 3#C`, row 3i + a, column 3k + b).
pub(crate) fn rows_jacobian_into(
    vertex_rows: &Mat<f64>,
    face_rows: &Mat<f64>,
    normals: &StretchedNormals,
    x: &[DVec3],
    out: &mut Mat<f64>,
) {
    let num_rows = vertex_rows.nrows();
    out.fill(0.0);
    for k in 0..vertex_rows.ncols() {
        let column = vertex_rows.col(k);
        for i in 0..num_rows {
            for a in 0..3 {
                out[(3 * i + a, 3 * k + a)] = column[i];
            }
        }
    }
    for (f, triangle) in normals.triangles().iter().enumerate() {
        let blocks = normals.face_jacobian(x, f);
        let column = face_rows.col(f);
        for (corner, block) in triangle.iter().zip(blocks) {
            let m = *corner as usize;
            for c in 0..3 {
                let d = block.col(c);
                let mut target = out.col_mut(3 * m + c);
                for i in 0..num_rows {
                    let w = column[i];
                    target[3 * i] += w * d.x;
                    target[3 * i + 1] += w * d.y;
                    target[3 * i + 2] += w * d.z;
                }
            }
        }
    }
}

/// out = φ_R x + ψ_R g (`#R`): each row summed over the columns in order (φ's, then ψ's), four
/// columns at a time per pass over the rows (the same additions, each row's partial sum kept in
/// a register across the four).
pub(crate) fn rows_of(
    vertex_rows: &Mat<f64>,
    face_rows: &Mat<f64>,
    x: &[DVec3],
    g: &[DVec3],
    out: &mut [DVec3],
) {
    out.iter_mut().for_each(|o| *o = DVec3::ZERO);
    add_columns_times_points(vertex_rows, x, out);
    add_columns_times_points(face_rows, g, out);
}

/// `out[i] += Σ_k matrix[i, k] · points[k]`, added in the order of k (`matrix`: `#out ×
/// #points`).
fn add_columns_times_points(matrix: &Mat<f64>, points: &[DVec3], out: &mut [DVec3]) {
    let mut blocks = points.chunks_exact(SIDE_BY_SIDE);
    for (b, block) in blocks.by_ref().enumerate() {
        let start = b * SIDE_BY_SIDE;
        let columns: [_; SIDE_BY_SIDE] = std::array::from_fn(|q| matrix.col(start + q));
        for (i, o) in out.iter_mut().enumerate() {
            let mut sum = *o;
            for (column, p) in columns.iter().zip(block) {
                sum += column[i] * *p;
            }
            *o = sum;
        }
    }
    let first = points.len() - points.len() % SIDE_BY_SIDE;
    for (k, p) in blocks.remainder().iter().enumerate() {
        let column = matrix.col(first + k);
        for (i, o) in out.iter_mut().enumerate() {
            *o += column[i] * *p;
        }
    }
}

/// Columns summed side by side in [`column_dots`] and rows in [`row_dots`].
const SIDE_BY_SIDE: usize = 4;

/// `out[c] = Σ_i matrix[i, c] · points[i]` for every column c of `matrix` (`#points × #out`),
/// each sum in the order of i — the bits of a fold over i — with four columns side by side, so
/// that their chains of additions overlap instead of waiting on each other. No allocation.
pub(crate) fn column_dots(matrix: &Mat<f64>, points: &[DVec3], out: &mut [DVec3]) {
    debug_assert_eq!(matrix.nrows(), points.len());
    debug_assert_eq!(matrix.ncols(), out.len());
    let first = out.len() - out.len() % SIDE_BY_SIDE;
    let mut blocks = out.chunks_exact_mut(SIDE_BY_SIDE);
    for (b, block) in blocks.by_ref().enumerate() {
        let start = b * SIDE_BY_SIDE;
        let columns: [_; SIDE_BY_SIDE] = std::array::from_fn(|q| matrix.col(start + q));
        let mut sums = [DVec3::ZERO; SIDE_BY_SIDE];
        for (i, p) in points.iter().enumerate() {
            for (sum, column) in sums.iter_mut().zip(&columns) {
                *sum += column[i] * *p;
            }
        }
        block.copy_from_slice(&sums);
    }
    for (c, o) in blocks.into_remainder().iter_mut().enumerate() {
        let column = matrix.col(first + c);
        *o = points
            .iter()
            .enumerate()
            .fold(DVec3::ZERO, |acc, (i, p)| acc + column[i] * *p);
    }
}

/// `out[r] = Σ_m matrix[r, m] · (x[m] − y[m])` for every row r of `matrix` (`#out × #x`),
/// each sum in the order of m — the bits of a fold over m — with four rows side by side (read
/// down the columns, where they are contiguous). No allocation.
pub(crate) fn row_dots(matrix: &Mat<f64>, x: &[DVec3], y: &[DVec3], out: &mut [DVec3]) {
    debug_assert_eq!(matrix.ncols(), x.len());
    debug_assert_eq!(matrix.nrows(), out.len());
    let first = out.len() - out.len() % SIDE_BY_SIDE;
    let mut blocks = out.chunks_exact_mut(SIDE_BY_SIDE);
    for (b, block) in blocks.by_ref().enumerate() {
        let start = b * SIDE_BY_SIDE;
        let mut sums = [DVec3::ZERO; SIDE_BY_SIDE];
        for (m, (xm, ym)) in x.iter().zip(y).enumerate() {
            let column = matrix.col(m);
            let d = *xm - *ym;
            for (q, sum) in sums.iter_mut().enumerate() {
                *sum += column[start + q] * d;
            }
        }
        block.copy_from_slice(&sums);
    }
    for (r, o) in blocks.into_remainder().iter_mut().enumerate() {
        let row = matrix.row(first + r);
        *o = x
            .iter()
            .zip(y)
            .enumerate()
            .fold(DVec3::ZERO, |acc, (m, (xm, ym))| acc + row[m] * (*xm - *ym));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_random::uniform;

    /// Four columns per pass, F_R(x) keeps the bits of one column at a time.
    #[test]
    fn rows_of_adds_the_columns_in_order() {
        let mut rng = uniform(9);
        let (rows, cage, faces) = (7, 6, 9);
        let phi = Mat::from_fn(rows, cage, |_, _| rng() - 0.5);
        let psi = Mat::from_fn(rows, faces, |_, _| rng() - 0.5);
        let x: Vec<DVec3> = (0..cage).map(|_| DVec3::new(rng(), rng(), rng())).collect();
        let g: Vec<DVec3> = (0..faces)
            .map(|_| DVec3::new(rng(), -rng(), rng()))
            .collect();
        let mut out = vec![DVec3::ZERO; rows];
        rows_of(&phi, &psi, &x, &g, &mut out);
        let mut expected = vec![DVec3::ZERO; rows];
        for (matrix, points) in [(&phi, &x), (&psi, &g)] {
            for (k, p) in points.iter().enumerate() {
                for (i, e) in expected.iter_mut().enumerate() {
                    *e += matrix[(i, k)] * *p;
                }
            }
        }
        assert_eq!(out, expected);
    }

    /// Side by side, the sums keep the bits of one fold each, edges included.
    #[test]
    fn dots_side_by_side_are_the_folds_bit_for_bit() {
        let mut rng = uniform(7);
        for (rows, columns) in [(9, 11), (5, 4), (3, 2), (6, 1)] {
            let matrix = Mat::from_fn(rows, columns, |_, _| rng() - 0.5);
            let points: Vec<DVec3> = (0..rows)
                .map(|_| DVec3::new(rng(), rng() - 0.5, 3.0 * rng()))
                .collect();
            let mut out = vec![DVec3::ZERO; columns];
            column_dots(&matrix, &points, &mut out);
            for (c, o) in out.iter().enumerate() {
                let column = matrix.col(c);
                let fold = points
                    .iter()
                    .enumerate()
                    .fold(DVec3::ZERO, |acc, (i, p)| acc + column[i] * *p);
                assert_eq!(*o, fold);
            }
            let x: Vec<DVec3> = (0..columns).map(|_| DVec3::splat(rng())).collect();
            let y: Vec<DVec3> = (0..columns)
                .map(|_| DVec3::new(rng(), 0.0, -rng()))
                .collect();
            let mut out = vec![DVec3::ZERO; rows];
            row_dots(&matrix, &x, &y, &mut out);
            for (r, o) in out.iter().enumerate() {
                let row = matrix.row(r);
                let fold = x
                    .iter()
                    .zip(&y)
                    .enumerate()
                    .fold(DVec3::ZERO, |acc, (m, (a, b))| acc + row[m] * (*a - *b));
                assert_eq!(*o, fold);
            }
        }
    }
}
