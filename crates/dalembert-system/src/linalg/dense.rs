//! Dense LU (partial pivoting) and Cholesky factorizations in storage allocated once (faer's
//! in-place kernels with caller-held scratch): refactoring and solving allocate nothing.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt;
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{Conj, Mat, MatMut, Par};

/// `P A = L U` of a square matrix, factored in place.
pub struct DenseLu {
    a: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    max_rhs: usize,
}

impl std::fmt::Debug for DenseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DenseLu").field("dim", &self.a.nrows()).finish()
    }
}

impl DenseLu {
    /// Storage for an `n × n` matrix solved against up to `max_rhs` right-hand sides at once.
    pub fn new(n: usize, max_rhs: usize) -> Self {
        let max_rhs = max_rhs.max(1);
        let solve = solve::solve_in_place_scratch::<usize, f64>(n, max_rhs, Par::Seq).or(
            solve::solve_transpose_in_place_scratch::<usize, f64>(n, max_rhs, Par::Seq),
        );
        DenseLu {
            a: Mat::zeros(n, n),
            perm: vec![0; n],
            perm_inv: vec![0; n],
            factor_buf: MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
                n,
                n,
                Par::Seq,
                Default::default(),
            )),
            solve_buf: MemBuffer::new(solve),
            max_rhs,
        }
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.a.nrows()
    }

    /// The matrix, for writing before [`DenseLu::factor`] (the factors after it).
    pub fn matrix_mut(&mut self) -> MatMut<'_, f64> {
        self.a.as_mut()
    }

    /// Factors in place; returns the smallest and largest pivot magnitudes (`U`'s diagonal), a
    /// cheap condition estimate.
    pub fn factor(&mut self) -> (f64, f64) {
        factor::lu_in_place(
            self.a.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            Par::Seq,
            MemStack::new(&mut self.factor_buf),
            Default::default(),
        );
        let (mut smallest, mut largest) = (f64::INFINITY, 0.0f64);
        for i in 0..self.a.nrows() {
            let p = self.a[(i, i)].abs();
            smallest = smallest.min(p);
            largest = largest.max(p);
        }
        if self.a.nrows() == 0 {
            smallest = 1.0;
            largest = 1.0;
        }
        (smallest, largest)
    }

    /// `X ← A⁻¹ X` for up to `max_rhs` columns.
    pub fn solve_in_place(&mut self, x: MatMut<'_, f64>) {
        self.solve_with(x, false);
    }

    /// `X ← A⁻ᵀ X` for up to `max_rhs` columns.
    pub fn solve_transpose_in_place(&mut self, x: MatMut<'_, f64>) {
        self.solve_with(x, true);
    }

    fn solve_with(&mut self, x: MatMut<'_, f64>, transpose: bool) {
        debug_assert!(x.ncols() <= self.max_rhs);
        let n = self.a.nrows();
        let perm = PermRef::new_checked(&self.perm, &self.perm_inv, n);
        let (a, stack) = (self.a.as_ref(), MemStack::new(&mut self.solve_buf));
        if transpose {
            solve::solve_transpose_in_place_with_conj(a, a, perm, Conj::No, x, Par::Seq, stack);
        } else {
            solve::solve_in_place_with_conj(a, a, perm, Conj::No, x, Par::Seq, stack);
        }
    }

    /// `x ← A⁻¹ x` for one vector.
    pub fn solve_vec(&mut self, x: &mut [f64]) {
        let n = x.len();
        self.solve_in_place(MatMut::from_column_major_slice_mut(x, n, 1));
    }

    /// `x ← A⁻ᵀ x` for one vector.
    pub fn solve_transpose_vec(&mut self, x: &mut [f64]) {
        let n = x.len();
        self.solve_transpose_in_place(MatMut::from_column_major_slice_mut(x, n, 1));
    }
}

/// `A = L Lᵀ` of a symmetric positive definite matrix, factored in place.
pub struct DenseCholesky {
    a: Mat<f64>,
    factor_buf: MemBuffer,
}

impl std::fmt::Debug for DenseCholesky {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DenseCholesky").field("dim", &self.a.nrows()).finish()
    }
}

impl DenseCholesky {
    /// Storage for an `n × n` matrix.
    pub fn new(n: usize) -> Self {
        DenseCholesky {
            a: Mat::zeros(n, n),
            factor_buf: MemBuffer::new(llt::factor::cholesky_in_place_scratch::<f64>(
                n,
                Par::Seq,
                Default::default(),
            )),
        }
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        self.a.nrows()
    }

    /// The matrix (its lower triangle is read), for writing before [`DenseCholesky::factor`].
    pub fn matrix_mut(&mut self) -> MatMut<'_, f64> {
        self.a.as_mut()
    }

    /// The matrix as owned storage (column-major; its lower triangle is read), for kernels that
    /// write whole columns.
    pub fn storage_mut(&mut self) -> &mut Mat<f64> {
        &mut self.a
    }

    /// Factors in place; `Err` when the matrix is not positive definite, with faer's error.
    pub fn factor(&mut self) -> Result<(), llt::factor::LltError> {
        llt::factor::cholesky_in_place(
            self.a.as_mut(),
            Default::default(),
            Par::Seq,
            MemStack::new(&mut self.factor_buf),
            Default::default(),
        )
        .map(|_| ())
    }

    /// After a successful [`DenseCholesky::factor`]: `(max L_kk / min L_kk)²`, a cheap estimate
    /// of the condition number (a lower bound of it; 1 for an empty matrix).
    pub fn condition_estimate(&self) -> f64 {
        let n = self.a.nrows();
        if n == 0 {
            return 1.0;
        }
        let (mut small, mut big) = (f64::INFINITY, 0.0f64);
        for k in 0..n {
            let d = self.a[(k, k)].abs();
            small = small.min(d);
            big = big.max(d);
        }
        (big / small).powi(2)
    }

    /// `x ← A⁻¹ x`.
    pub fn solve_vec(&mut self, x: &mut [f64]) {
        let n = x.len();
        llt::solve::solve_in_place_with_conj(
            self.a.as_ref(),
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
            Par::Seq,
            MemStack::new(&mut []),
        );
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// LU and transpose solves of a non-symmetric matrix, and Cholesky of `AᵀA + I`, against the
    /// products they invert.
    #[test]
    fn solves_invert_their_products() {
        let n = 5;
        let a = Mat::from_fn(n, n, |i, j| {
            ((3 * i + 7 * j) % 11) as f64 - 4.0 + if i == j { 9.0 } else { 0.0 }
        });
        let x: Vec<f64> = (0..n).map(|i| i as f64 - 1.5).collect();
        let mut lu = DenseLu::new(n, 1);
        lu.matrix_mut().copy_from(&a);
        lu.factor();
        let mut b: Vec<f64> = (0..n).map(|i| (0..n).map(|j| a[(i, j)] * x[j]).sum()).collect();
        lu.solve_vec(&mut b);
        let mut bt: Vec<f64> = (0..n).map(|i| (0..n).map(|j| a[(j, i)] * x[j]).sum()).collect();
        lu.solve_transpose_vec(&mut bt);
        let spd = Mat::from_fn(n, n, |i, j| {
            (0..n).map(|k| a[(k, i)] * a[(k, j)]).sum::<f64>() + f64::from(i == j)
        });
        let mut ch = DenseCholesky::new(n);
        ch.matrix_mut().copy_from(&spd);
        ch.factor().unwrap();
        let mut c: Vec<f64> = (0..n).map(|i| (0..n).map(|j| spd[(i, j)] * x[j]).sum()).collect();
        ch.solve_vec(&mut c);
        for i in 0..n {
            assert!((b[i] - x[i]).abs() < 1e-12 && (bt[i] - x[i]).abs() < 1e-12 && (c[i] - x[i]).abs() < 1e-12);
        }
    }
}
