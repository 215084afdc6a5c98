//! A dense LU factorisation with partial pivoting into caller-owned storage, for the small
//! `3#C × 3#C` Jacobians of the Green-coordinates Newton iterations: factorise and solve without
//! allocating, so that an event that refactorises stays allocation-free.

use crate::error::RigError;

/// LU factors of an `n × n` matrix, packed column-major (unit lower L below the diagonal, U on
/// and above), with the row interchanges of partial pivoting.
#[derive(Debug, Clone, PartialEq)]
pub struct DenseLu {
    n: usize,
    /// The matrix on [`DenseLu::matrix_mut`], its factors after [`DenseLu::factorise`].
    values: Vec<f64>,
    /// Row interchanges: at step j, row j was swapped with row `pivots[j]` (LAPACK's ipiv).
    pivots: Vec<usize>,
    factorised: bool,
}

impl DenseLu {
    /// Storage for `n × n` matrices.
    pub fn new(n: usize) -> Self {
        Self {
            n,
            values: vec![0.0; n * n],
            pivots: vec![0; n],
            factorised: false,
        }
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

    /// Factorises the matrix in place. Errors when a pivot is zero or the matrix is not
    /// finite (the factors are then unusable).
    pub fn factorise(&mut self) -> Result<(), RigError> {
        let n = self.n;
        let a = &mut self.values;
        self.factorised = false;
        let mut largest: f64 = 0.0;
        for j in 0..n {
            let column = &a[j * n..(j + 1) * n];
            let (p, pivot) = column[j..]
                .iter()
                .enumerate()
                .fold((j, 0.0f64), |best, (i, v)| {
                    if v.abs() > best.1 {
                        (j + i, v.abs())
                    } else {
                        best
                    }
                });
            largest = largest.max(pivot);
            if pivot.is_nan() || pivot <= f64::EPSILON * largest * n as f64 {
                return Err(RigError::Invalid(format!(
                    "the Green-coordinates Jacobian ({n} × {n}) is singular at column {j} \
                     (largest pivot {pivot:.3e}): the cage fit has no unique solution"
                )));
            }
            self.pivots[j] = p;
            if p != j {
                for c in 0..n {
                    a.swap(c * n + j, c * n + p);
                }
            }
            let diagonal = a[j * n + j];
            for v in &mut a[j * n + j + 1..(j + 1) * n] {
                *v /= diagonal;
            }
            let (done, rest) = a.split_at_mut((j + 1) * n);
            let pivot_column = &done[j * n + j + 1..(j + 1) * n];
            for column in rest.chunks_exact_mut(n) {
                let factor = column[j];
                if factor != 0.0 {
                    for (v, l) in column[j + 1..].iter_mut().zip(pivot_column) {
                        *v -= l * factor;
                    }
                }
            }
        }
        self.factorised = true;
        Ok(())
    }

    /// Solves A x = b in place (`x` holds b on entry, `n` long). Requires the factors.
    pub fn solve(&self, x: &mut [f64]) {
        let n = self.n;
        debug_assert!(self.factorised);
        for (j, &p) in self.pivots.iter().enumerate() {
            x.swap(j, p);
        }
        let a = &self.values;
        for c in 0..n {
            let v = x[c];
            if v != 0.0 {
                for (xr, l) in x[c + 1..].iter_mut().zip(&a[c * n + c + 1..(c + 1) * n]) {
                    *xr -= l * v;
                }
            }
        }
        for c in (0..n).rev() {
            let v = x[c] / a[c * n + c];
            x[c] = v;
            for (xr, u) in x[..c].iter_mut().zip(&a[c * n..c * n + c]) {
                *xr -= u * v;
            }
        }
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
        let mut lu = DenseLu::new(n);
        lu.matrix_mut().copy_from_slice(&matrix);
        lu.factorise().unwrap();
        lu.solve(&mut b);
        for (x, t) in b.iter().zip(&x_true) {
            assert!((x - t).abs() < 1e-12, "{x} vs {t}");
        }
        let mut singular = DenseLu::new(2);
        singular.matrix_mut().copy_from_slice(&[1.0, 2.0, 2.0, 4.0]);
        assert!(singular.factorise().is_err());
        assert!(!singular.is_factorised());
    }
}
