//! A dense LU factorisation with partial pivoting into caller-owned storage, for the small
//! `3#C × 3#C` systems of the cage fits: the Jacobians and Hessians of the Green-coordinates
//! Newton iterations and CageRev's Eq. 19. Factorise and solve without allocating, so that an
//! event that refactorises stays allocation-free.
//!
//! The factorisation is faer's blocked, recursive LU (`lu_in_place`), run sequentially into
//! scratch allocated once: on the Arm's cage (n = 174) it takes about a fifth of the time of the
//! column-by-column elimination this file held before, which was the largest part of a Green
//! animation frame (`cagerig bench --coords green`).

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
        factor::lu_in_place(
            MatMut::from_column_major_slice_mut(&mut self.values, n, n),
            &mut self.forward,
            &mut self.inverse,
            faer::Par::Seq,
            MemStack::new(&mut self.scratch),
            Default::default(),
        );
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

#[cfg(test)]
mod tests {
    use super::*;
    use crate::test_random::uniform;

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
