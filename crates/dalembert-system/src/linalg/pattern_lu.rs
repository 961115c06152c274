//! LU of a square matrix given by a fixed list of entries, dense up to a size and sparse above:
//! the caller writes values in its own entry order ([`PatternLu::values_mut`]), and
//! [`PatternLu::factor`] scatters them into the dense storage ([`DenseLu`]) or the compressed
//! columns of the sparse LU ([`SparseLu`], symbolic analysis once). Neither refactoring nor solving
//! allocates. Used by the implicit integrator for its iteration matrix, whose pattern the system
//! fixes at setup and whose values change every refactorization.

use super::{DenseLu, LinalgError, SparseLu};

/// Square matrix with a fixed entry list, factored by dense or sparse LU.
#[derive(Debug)]
pub struct PatternLu {
    entries: Vec<(usize, usize)>,
    values: Vec<f64>,
    storage: Storage,
}

#[derive(Debug)]
enum Storage {
    Dense(Box<DenseLu>),
    /// The sparse LU and, per entry, its index in the compressed values.
    Sparse(Box<SparseLu>, Vec<usize>),
}

impl PatternLu {
    /// Dimensions up to which the dense LU is used by default: measured on the implicit
    /// integrator's iteration matrix of planar chains (the dense LU of 4 links, 20 unknowns, is
    /// faster than the sparse one; at 8 links, 40 unknowns, they are even).
    pub const DENSE_LIMIT: usize = 40;

    /// A `dim × dim` matrix with non-zeros at `entries` (duplicates allowed: their values add),
    /// dense when `dim ≤ dense_limit`.
    pub fn new(dim: usize, entries: Vec<(usize, usize)>, dense_limit: usize) -> Result<Self, LinalgError> {
        let storage = if dim <= dense_limit {
            Storage::Dense(Box::new(DenseLu::new(dim, 1)))
        } else {
            let lu = SparseLu::new(dim, entries.iter().copied())?;
            let positions = entries.iter().map(|&(r, c)| lu.position(r, c)).collect();
            Storage::Sparse(Box::new(lu), positions)
        };
        Ok(PatternLu {
            values: vec![0.0; entries.len()],
            entries,
            storage,
        })
    }

    /// The dimension.
    pub fn dim(&self) -> usize {
        match &self.storage {
            Storage::Dense(lu) => lu.dim(),
            Storage::Sparse(lu, _) => lu.dim(),
        }
    }

    /// True when the sparse LU is in use.
    pub fn is_sparse(&self) -> bool {
        matches!(self.storage, Storage::Sparse(..))
    }

    /// The entries, in the order of [`PatternLu::values_mut`].
    pub fn entries(&self) -> &[(usize, usize)] {
        &self.entries
    }

    /// The values of the entries, in the order given to [`PatternLu::new`], for writing before
    /// [`PatternLu::factor`].
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Factors the current values. `Err` when the matrix is singular (a zero or non-finite pivot).
    pub fn factor(&mut self) -> Result<(), LinalgError> {
        match &mut self.storage {
            Storage::Dense(lu) => {
                let mut a = lu.matrix_mut();
                a.fill(0.0);
                for (&(r, c), &v) in self.entries.iter().zip(&self.values) {
                    a[(r, c)] += v;
                }
                let (smallest, largest) = lu.factor();
                if !(smallest > 0.0 && largest.is_finite()) {
                    return Err(LinalgError::Singular(format!(
                        "dense LU: pivots from {smallest:.3e} to {largest:.3e}"
                    )));
                }
                Ok(())
            }
            Storage::Sparse(lu, positions) => {
                let dst = lu.values_mut();
                dst.fill(0.0);
                for (&p, &v) in positions.iter().zip(&self.values) {
                    dst[p] += v;
                }
                lu.factor()?;
                let (smallest, largest) = lu.pivot_range();
                if !(smallest > 0.0 && largest.is_finite()) {
                    return Err(LinalgError::Singular(format!(
                        "sparse LU: pivots from {smallest:.3e} to {largest:.3e}"
                    )));
                }
                Ok(())
            }
        }
    }

    /// `x ← A⁻¹ x` with the factors of the last successful [`PatternLu::factor`].
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        match &mut self.storage {
            Storage::Dense(lu) => lu.solve_vec(x),
            Storage::Sparse(lu, _) => lu.solve_in_place(x),
        }
    }
}
