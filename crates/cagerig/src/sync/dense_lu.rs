//! A dense LU factorisation with partial pivoting into caller-owned storage, for the small
//! `3#C × 3#C` systems of the cage fits: the Jacobians and Hessians of the Green-coordinates
//! Newton iterations and CageRev's Eq. 19. Factorise and solve without allocating, so that an
//! event that refactorises stays allocation-free.
//!
//! The factorisation is faer's blocked, recursive LU (`lu_in_place`), run sequentially into
//! scratch allocated once: on the Arm's cage (n = 174) it takes about a fifth of the time of a
//! column-by-column elimination, which was the largest part of a Green animation frame
//! (`cagerig bench --coords green`). On the web target faer has no SIMD kernels and runs its
//! portable ones; there the column-by-column elimination [`eliminate_by_columns`] is the faster
//! (LLVM vectorises its updates with `simd128`): a 300 × 300 LU, the regularised CageRev's of
//! the Fox, takes 2.5 ms against faer's 3.2–4.3 ms in V8 (`docs/web.md`). Both kernels give
//! the same factors up to round-off (tested natively).

use faer::MatMut;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};

use crate::error::RigError;

/// LU factors of an `n × n` matrix, packed column-major (unit lower L below the diagonal, U on
/// and above), with the row permutation of partial pivoting.
pub struct DenseLu {
    n: usize,
    /// What the matrix is, for errors ("the Green-coordinates Jacobian").
    what: &'static str,
    /// The matrix on [`DenseLu::matrix_mut`], its factors after [`DenseLu::factorise`].
    values: Vec<f64>,
    /// Row `forward[k]` of the matrix is row k of L·U; `inverse` is its inverse.
    forward: Vec<usize>,
    inverse: Vec<usize>,
    /// faer's scratch for the factorisation and for one right-hand side.
    scratch: MemBuffer,
    factorised: bool,
}

impl std::fmt::Debug for DenseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DenseLu")
            .field("n", &self.n)
            .field("what", &self.what)
            .field("factorised", &self.factorised)
            .finish_non_exhaustive()
    }
}

impl Clone for DenseLu {
    fn clone(&self) -> Self {
        Self {
            n: self.n,
            what: self.what,
            values: self.values.clone(),
            forward: self.forward.clone(),
            inverse: self.inverse.clone(),
            scratch: MemBuffer::new(Self::scratch_size(self.n)),
            factorised: self.factorised,
        }
    }
}

impl PartialEq for DenseLu {
    fn eq(&self, other: &Self) -> bool {
        self.n == other.n
            && self.values == other.values
            && self.forward == other.forward
            && self.factorised == other.factorised
    }
}

impl DenseLu {
    /// Storage for `n × n` matrices; `what` names the matrix in errors ("the
    /// Green-coordinates Jacobian").
    pub fn new(n: usize, what: &'static str) -> Self {
        Self {
            n,
            what,
            values: vec![0.0; n * n],
            forward: (0..n).collect(),
            inverse: (0..n).collect(),
            scratch: MemBuffer::new(Self::scratch_size(n)),
            factorised: false,
        }
    }

    fn scratch_size(n: usize) -> faer::dyn_stack::StackReq {
        factor::lu_in_place_scratch::<usize, f64>(n, n, faer::Par::Seq, Default::default()).or(
            solve::solve_in_place_scratch::<usize, f64>(n, 1, faer::Par::Seq),
        )
    }

    /// The matrix to fill (column-major, `n × n`; entry (r, c) at `c·n + r`). Invalidates the
    /// factors.
    pub fn matrix_mut(&mut self) -> &mut [f64] {
        self.factorised = false;
        &mut self.values
    }

    /// Whether [`DenseLu::factorise`] succeeded since the matrix was last written.
    pub fn is_factorised(&self) -> bool {
        self.factorised
    }

    /// Forgets the factors (the next solve needs a new matrix).
    pub fn invalidate(&mut self) {
        self.factorised = false;
    }

    /// Factorises the matrix in place. Errors when a pivot is zero against the largest pivot
    /// before it (|u_jj| ≤ ε·n·max_{k≤j} |u_kk|) or the matrix is not finite (the factors are
    /// then unusable).
    pub fn factorise(&mut self) -> Result<(), RigError> {
        let (n, what) = (self.n, self.what);
        self.factorised = false;
        if self.values.iter().any(|v| !v.is_finite()) {
            return Err(RigError::Invalid(format!(
                "{what} ({n} × {n}) is not finite: the cage fit has no unique solution"
            )));
        }
        #[cfg(not(target_arch = "wasm32"))]
        factor::lu_in_place(
            MatMut::from_column_major_slice_mut(&mut self.values, n, n),
            &mut self.forward,
            &mut self.inverse,
            faer::Par::Seq,
            MemStack::new(&mut self.scratch),
            Default::default(),
        );
        #[cfg(target_arch = "wasm32")]
        eliminate_by_columns(&mut self.values, n, &mut self.forward, &mut self.inverse);
        crate::vector_registers::clear_upper_halves();
        let mut largest: f64 = 0.0;
        for j in 0..n {
            let pivot = self.values[j * n + j].abs();
            largest = largest.max(pivot);
            if pivot.is_nan() || pivot <= f64::EPSILON * largest * n as f64 {
                return Err(RigError::Invalid(format!(
                    "{what} ({n} × {n}) is singular at column {j} (pivot {pivot:.3e}, largest \
                     {largest:.3e}): the cage fit has no unique solution"
                )));
            }
        }
        self.factorised = true;
        Ok(())
    }

    /// The diagonal of U (`n`), once factorised.
    pub fn pivots(&self) -> impl Iterator<Item = f64> + '_ {
        (0..self.n).map(|j| self.values[j * self.n + j])
    }

    /// Solves A x = b in place (`x` holds b on entry, `n` long). Requires the factors.
    pub fn solve(&mut self, x: &mut [f64]) {
        let n = self.n;
        debug_assert!(self.factorised);
        let packed = faer::MatRef::from_column_major_slice(&self.values, n, n);
        solve::solve_in_place(
            packed,
            packed,
            faer::perm::PermRef::new_checked(&self.forward, &self.inverse, n),
            MatMut::from_column_major_slice_mut(x, n, 1),
            faer::Par::Seq,
            MemStack::new(&mut self.scratch),
        );
        crate::vector_registers::clear_upper_halves();
    }
}

/// LU with partial pivoting of the `n × n` column-major `values` in place, column by column
/// (right-looking: each column's multipliers, then the rank-1 update of the columns to its
/// right, one contiguous column at a time), in the packing and permutation of faer's
/// `lu_in_place`: unit L below the diagonal, U on and above, row `forward[k]` of the matrix
/// is row k of L·U and `inverse` is its inverse. A zero pivot leaves its column unscaled (the
/// caller's pivot check refuses it). The web target's kernel (see the module docs).
#[cfg_attr(not(any(target_arch = "wasm32", test)), expect(dead_code))]
fn eliminate_by_columns(
    values: &mut [f64],
    n: usize,
    forward: &mut [usize],
    inverse: &mut [usize],
) {
    for (k, f) in forward.iter_mut().enumerate() {
        *f = k;
    }
    for k in 0..n {
        let column = &values[k * n..(k + 1) * n];
        let (mut pivot_row, mut largest) = (k, column[k].abs());
        for (i, v) in column.iter().enumerate().skip(k + 1) {
            if v.abs() > largest {
                (pivot_row, largest) = (i, v.abs());
            }
        }
        if pivot_row != k {
            forward.swap(pivot_row, k);
            for j in 0..n {
                values.swap(j * n + k, j * n + pivot_row);
            }
        }
        let pivot = values[k * n + k];
        if pivot != 0.0 {
            let inverse_pivot = 1.0 / pivot;
            for v in &mut values[k * n + k + 1..(k + 1) * n] {
                *v *= inverse_pivot;
            }
        }
        let (done, rest) = values.split_at_mut((k + 1) * n);
        let multipliers = &done[k * n + k + 1..];
        for column in rest.chunks_exact_mut(n) {
            let u = column[k];
            if u != 0.0 {
                for (v, l) in column[k + 1..].iter_mut().zip(multipliers) {
                    *v -= u * *l;
                }
            }
        }
    }
    for (k, &f) in forward.iter().enumerate() {
        inverse[f] = k;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_random::uniform;

    /// The web target's kernel gives faer's factors up to round-off, with the same pivots.
    #[test]
    fn column_elimination_matches_faer() {
        let n = 37;
        let mut rng = uniform(5);
        let matrix: Vec<f64> = (0..n * n).map(|_| rng() - 0.5).collect();
        let mut faer_lu = DenseLu::new(n, "a test matrix");
        faer_lu.matrix_mut().copy_from_slice(&matrix);
        faer_lu.factorise().unwrap();
        let mut values = matrix.clone();
        let (mut forward, mut inverse) = (vec![0; n], vec![0; n]);
        eliminate_by_columns(&mut values, n, &mut forward, &mut inverse);
        assert_eq!(forward, faer_lu.forward);
        assert_eq!(inverse, faer_lu.inverse);
        let worst = values
            .iter()
            .zip(&faer_lu.values)
            .fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        assert!(worst < 1e-12, "largest difference {worst:e}");
    }

    #[test]
    fn solves_a_random_system_and_refuses_a_singular_one() {
        let n = 17;
        let mut rng = uniform(11);
        let matrix: Vec<f64> = (0..n * n).map(|_| rng() - 0.5).collect();
        let x_true: Vec<f64> = (0..n).map(|i| i as f64 - 3.0).collect();
        let mut b = vec![0.0; n];
        for c in 0..n {
            for r in 0..n {
                b[r] += matrix[c * n + r] * x_true[c];
            }
        }
        let mut lu = DenseLu::new(n, "a test matrix");
        lu.matrix_mut().copy_from_slice(&matrix);
        lu.factorise().unwrap();
        lu.solve(&mut b);
        for (x, t) in b.iter().zip(&x_true) {
            assert!((x - t).abs() < 1e-12, "{x} vs {t}");
        }
        let mut singular = DenseLu::new(2, "a test matrix");
        singular.matrix_mut().copy_from_slice(&[1.0, 2.0, 2.0, 4.0]);
        assert!(singular.factorise().is_err());
        assert!(!singular.is_factorised());
    }
}
