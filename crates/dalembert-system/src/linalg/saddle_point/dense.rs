//! Dense back end: LU with partial pivoting of the assembled `(n+m)²` KKT matrix, factored in place
//! in storage allocated once.

use super::SingularKkt;
use crate::linalg::SmallLu;

/// Largest `n + m` factored by the unblocked LU.
const SMALL: usize = 64;
use crate::{BlockDiagonal, ConstraintPattern, ConstraintValues};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::lu::partial_pivoting::{factor, solve};
use faer::perm::PermRef;
use faer::{Mat, MatMut, Par};

pub(crate) struct DenseKkt {
    n: usize,
    /// Unblocked LU for small matrices (`n + m ≤ SMALL`), else faer's.
    small: Option<SmallLu>,
    a: Mat<f64>,
    perm: Vec<usize>,
    perm_inv: Vec<usize>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    /// Pivots below `pivot_tolerance × largest pivot` mean a singular matrix.
    pivot_tolerance: f64,
}

impl DenseKkt {
    pub fn new(n: usize, m: usize, pivot_tolerance: f64) -> Self {
        let k = n + m;
        let small = (k <= SMALL).then(|| SmallLu::new(k));
        let k = if small.is_some() { 0 } else { k };
        DenseKkt {
            n,
            small,
            a: Mat::zeros(k, k),
            perm: vec![0; k],
            perm_inv: vec![0; k],
            factor_buf: MemBuffer::new(factor::lu_in_place_scratch::<usize, f64>(
                k,
                k,
                Par::Seq,
                Default::default(),
            )),
            solve_buf: MemBuffer::new(solve::solve_in_place_scratch::<usize, f64>(k, 1, Par::Seq)),
            pivot_tolerance,
        }
    }

    pub fn factor(
        &mut self,
        mass: &BlockDiagonal,
        pattern: &ConstraintPattern,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        let n = self.n;
        if let Some(lu) = &mut self.small {
            let k = n + pattern.rows();
            lu.a.iter_mut().for_each(|v| *v = 0.0);
            for (r, c, v) in mass.entries() {
                lu.a[r * k + c] = v;
            }
            for (&(r, c), &v) in pattern.entries().iter().zip(&vals.jacobian) {
                lu.a[(n + r) * k + c] += v;
                lu.a[c * k + n + r] += v;
            }
            let (smallest, largest) = lu.factor();
            if !(smallest.is_finite() && largest.is_finite()) || smallest <= self.pivot_tolerance * largest {
                return Err(SingularKkt(format!("LU pivot ratio {:.3e}", smallest / largest)));
            }
            return Ok(());
        }
        let k = self.a.nrows();
        self.a.fill(0.0);
        for (r, c, v) in mass.entries() {
            self.a[(r, c)] = v;
        }
        for (&(r, c), &v) in pattern.entries().iter().zip(&vals.jacobian) {
            self.a[(n + r, c)] += v;
            self.a[(c, n + r)] += v;
        }
        factor::lu_in_place(
            self.a.as_mut(),
            &mut self.perm,
            &mut self.perm_inv,
            Par::Seq,
            MemStack::new(&mut self.factor_buf),
            Default::default(),
        );
        let mut largest = 0.0f64;
        let mut smallest = f64::INFINITY;
        for i in 0..k {
            let p = self.a[(i, i)].abs();
            largest = largest.max(p);
            smallest = smallest.min(p);
        }
        if !(smallest.is_finite() && largest.is_finite()) || smallest <= self.pivot_tolerance * largest {
            return Err(SingularKkt(format!("LU pivot ratio {:.3e}", smallest / largest)));
        }
        Ok(())
    }

    pub fn solve(&mut self, x: &mut [f64]) {
        if let Some(lu) = &self.small {
            lu.solve(x);
            return;
        }
        let k = x.len();
        let rhs = MatMut::from_column_major_slice_mut(x, k, 1);
        // SAFETY-free: the permutation arrays were written by `lu_in_place` and are valid inverses.
        let perm = PermRef::new_checked(&self.perm, &self.perm_inv, k);
        solve::solve_in_place(
            self.a.as_ref(),
            self.a.as_ref(),
            perm,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
    }
}
