//! The fitting rows of a Green cage map, `F_R(x) = φ_R x + ψ_R g(x)`, and their Jacobian: shared
//! by CageUp's fit ([`super::GreenCageFit`]), CageRev ([`super::reverser`])
//! and SkelUp's joints (the same form with Ψ_φ, Ψ_ψ).

use faer::Mat;
use glam::DVec3;

use crate::coords::stretched_normals::StretchedNormals;
use crate::simd_dispatch::simd_dispatch;

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

simd_dispatch! {
    /// `out[i] += Σ_k matrix[i, k] · points[k]`, added in the order of k (`matrix`: `#out ×
    /// #points`): up to [`ROW_LANES`] rows side by side (then [`TAIL_LANES`], then one at a
    /// time for the last rows), each down the contiguous columns, so that
    /// their sums are the lanes of one vector instruction per column and coordinate (the same
    /// product and sum per term as one row at a time, so the same bits on every tier).
    fn add_columns_times_points(
        matrix: &Mat<f64>,
        points: &[DVec3],
        out: &mut [DVec3]
    ) => add_columns_times_points_generic;
    avx512f: add_columns_times_points_avx512;
    avx2: add_columns_times_points_avx2;
}

/// Rows summed side by side in [`add_columns_times_points`]: four AVX-512 registers of f64 per
/// coordinate, so that twelve chains of additions overlap instead of each waiting on its last
/// addition.
const ROW_LANES: usize = 32;
/// Rows side by side in the rows left after the blocks of [`ROW_LANES`]: one AVX-512 register.
const TAIL_LANES: usize = 8;

#[inline(always)]
fn add_columns_times_points_generic(matrix: &Mat<f64>, points: &[DVec3], out: &mut [DVec3]) {
    debug_assert_eq!(matrix.nrows(), out.len());
    debug_assert_eq!(matrix.ncols(), points.len());
    let rows = out.len();
    let mut start = 0;
    while rows - start >= ROW_LANES {
        add_columns_to_rows::<ROW_LANES>(matrix, points, start, &mut out[start..start + ROW_LANES]);
        start += ROW_LANES;
    }
    while rows - start >= TAIL_LANES {
        add_columns_to_rows::<TAIL_LANES>(
            matrix,
            points,
            start,
            &mut out[start..start + TAIL_LANES],
        );
        start += TAIL_LANES;
    }
    while start < rows {
        add_columns_to_rows::<1>(matrix, points, start, &mut out[start..start + 1]);
        start += 1;
    }
}

/// Rows `start..start + N` of [`add_columns_times_points`] (`block`), side by side.
#[inline(always)]
fn add_columns_to_rows<const N: usize>(
    matrix: &Mat<f64>,
    points: &[DVec3],
    start: usize,
    block: &mut [DVec3],
) {
    let (mut x, mut y, mut z) = ([0.0f64; N], [0.0; N], [0.0; N]);
    for (l, o) in block.iter().enumerate() {
        (x[l], y[l], z[l]) = (o.x, o.y, o.z);
    }
    for (k, p) in points.iter().enumerate() {
        let column = &matrix.col_as_slice(k)[start..start + N];
        for l in 0..N {
            x[l] += column[l] * p.x;
            y[l] += column[l] * p.y;
            z[l] += column[l] * p.z;
        }
    }
    for (l, o) in block.iter_mut().enumerate() {
        *o = DVec3::new(x[l], y[l], z[l]);
    }
}

/// `out[c] = Σ_i transposed[c, i] · points[i]` for every column c of the matrix whose
/// transpose is `transposed` (`#out × #points`, that is Aᵀ·points for A `#points × #out`),
/// each sum in the order of i from zero (the bits of one fold over i per column), read down
/// the contiguous columns of Aᵀ ([`add_columns_times_points`]). No allocation.
pub(crate) fn transposed_times_points(transposed: &Mat<f64>, points: &[DVec3], out: &mut [DVec3]) {
    out.fill(DVec3::ZERO);
    add_columns_times_points(transposed, points, out);
}

/// Rows summed side by side in [`row_dots`].
const SIDE_BY_SIDE: usize = 4;

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

    /// Rows side by side, F_R(x) keeps the bits of one row and one column at a time: in blocks
    /// of 32 rows, of 8, and one at a time.
    #[test]
    fn rows_of_adds_the_columns_in_order() {
        let mut rng = uniform(9);
        for (rows, cage, faces) in [(7, 6, 9), (19, 6, 9), (16, 3, 1), (77, 5, 7), (32, 2, 3)] {
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
    }

    /// Every instruction-set tier of the side-by-side rows gives the baseline's bits.
    #[test]
    #[expect(
        unsafe_code,
        reason = "the test calls the #[target_feature] tiers after detecting them"
    )]
    fn every_tier_adds_the_columns_with_the_same_bits() {
        let mut rng = uniform(5);
        // Two blocks of 32 rows, one of 8 and 5 rows one at a time.
        let (rows, columns) = (77, 13);
        let matrix = Mat::from_fn(rows, columns, |_, _| rng() - 0.5);
        let points: Vec<DVec3> = (0..columns)
            .map(|_| DVec3::new(rng(), -rng(), 1e3 * rng()))
            .collect();
        let start: Vec<DVec3> = (0..rows).map(|_| DVec3::splat(rng())).collect();
        let mut baseline = start.clone();
        add_columns_times_points_generic(&matrix, &points, &mut baseline);
        #[cfg(target_arch = "x86_64")]
        {
            let cpu = crate::simd_dispatch::cpu();
            if cpu.avx2() {
                let mut out = start.clone();
                // SAFETY: feature checked.
                unsafe { add_columns_times_points_avx2(&matrix, &points, &mut out) };
                assert_eq!(out, baseline);
            }
            if cpu.avx512f() {
                let mut out = start.clone();
                // SAFETY: feature checked.
                unsafe { add_columns_times_points_avx512(&matrix, &points, &mut out) };
                assert_eq!(out, baseline);
            }
        }
        let mut out = start;
        add_columns_times_points(&matrix, &points, &mut out);
        assert_eq!(out, baseline);
    }

    /// Side by side, the sums keep the bits of one fold each, edges included.
    #[test]
    fn dots_side_by_side_are_the_folds_bit_for_bit() {
        let mut rng = uniform(7);
        for (rows, columns) in [(9, 11), (5, 4), (3, 2), (6, 1), (12, 21), (10, 45)] {
            let matrix = Mat::from_fn(rows, columns, |_, _| rng() - 0.5);
            let points: Vec<DVec3> = (0..rows)
                .map(|_| DVec3::new(rng(), rng() - 0.5, 3.0 * rng()))
                .collect();
            let mut out = vec![DVec3::ZERO; columns];
            transposed_times_points(&matrix.transpose().to_owned(), &points, &mut out);
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
