//! Dense back end: LU with partial pivoting of the assembled `(n+m)²` KKT matrix, factored in place
//! in storage allocated once.

use super::SingularKkt;
use crate::linalg::{DenseLu, SmallLu};

/// Largest `n + m` factored by the unblocked LU.
const SMALL: usize = 64;
use crate::{BlockDiagonal, ConstraintPattern, ConstraintValues};

pub(crate) struct DenseKkt {
    n: usize,
    /// Unblocked LU for small matrices (`n + m ≤ SMALL`), else faer's.
    small: Option<SmallLu>,
    /// faer's LU in held storage for larger matrices.
    lu: DenseLu,
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
            lu: DenseLu::new(k, 1),
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
        {
            let mut a = self.lu.matrix_mut();
            a.fill(0.0);
            for (r, c, v) in mass.entries() {
                a[(r, c)] = v;
            }
            for (&(r, c), &v) in pattern.entries().iter().zip(&vals.jacobian) {
                a[(n + r, c)] += v;
                a[(c, n + r)] += v;
            }
        }
        let (smallest, largest) = self.lu.factor();
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
        self.lu.solve_vec(x);
    }
}
