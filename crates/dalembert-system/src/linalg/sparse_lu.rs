//! Sparse LU (faer) of a square matrix with a fixed pattern: the compressed-column structure, the
//! symbolic analysis and the scratch are built once; each [`SparseLu::factor`] refactors the values
//! numerically without allocating.
//!
//! The factorization is always faer's *simplicial* LU: its supernodal numeric factorization (which
//! faer picks by a flop-ratio heuristic for patterns with dense blocks) allocates on every call in
//! faer 0.24 (measured by `tests/allocation.rs`: 190 allocations per factorization of the
//! amalgamated matrix of a chain of 64 links).

use super::LinalgError;
use crate::sparse_pattern::{compress_columns, entry_position};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};

/// A square sparse matrix with a fixed pattern and its LU factors.
pub struct SparseLu {
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
}

impl std::fmt::Debug for SparseLu {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseLu")
            .field("dim", &self.dim)
            .field("entries", &self.values.len())
            .finish()
    }
}

impl SparseLu {
    /// The pattern of a `dim × dim` matrix from its `(row, column)` entries (duplicates merged) and
    /// its symbolic analysis.
    pub fn new(dim: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Result<Self, LinalgError> {
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); dim];
        for (r, c) in entries {
            cols[c].push(r);
        }
        let (col_ptr, row_idx) = compress_columns(cols);
        let symbolic = {
            let s = SymbolicSparseColMatRef::new_checked(dim, dim, &col_ptr, None, &row_idx);
            let params = faer::sparse::linalg::lu::LuSymbolicParams {
                supernodal_flop_ratio_threshold: faer::sparse::linalg::SupernodalThreshold::FORCE_SIMPLICIAL,
                ..Default::default()
            };
            factorize_symbolic_lu(s, params).map_err(|source| LinalgError::Symbolic {
                what: "symbolic analysis of the sparse LU",
                source,
            })?
        };
        let factor_buf = MemBuffer::new(symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()));
        let solve_buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        Ok(SparseLu {
            dim,
            values: vec![0.0; row_idx.len()],
            col_ptr,
            row_idx,
            symbolic,
            numeric: NumericLu::new(),
            factor_buf,
            solve_buf,
        })
    }

    /// The matrix dimension.
    pub fn dim(&self) -> usize {
        self.dim
    }

    /// Index in [`SparseLu::values_mut`] of entry `(r, c)` (which must be in the pattern).
    pub fn position(&self, r: usize, c: usize) -> usize {
        entry_position(&self.col_ptr, &self.row_idx, r, c)
    }

    /// The values, in compressed-column order, for writing before [`SparseLu::factor`].
    pub fn values_mut(&mut self) -> &mut [f64] {
        &mut self.values
    }

    /// Numeric LU of the current values (symbolic analysis reused). Allocates nothing.
    pub fn factor(&mut self) -> Result<(), LinalgError> {
        let s = SymbolicSparseColMatRef::new_checked(self.dim, self.dim, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(s, &self.values);
        self.symbolic
            .factorize_numeric_lu(
                &mut self.numeric,
                a,
                Par::Seq,
                MemStack::new(&mut self.factor_buf),
                Default::default(),
            )
            .map(|_| ())
            .map_err(|source| LinalgError::SparseLu {
                what: "numeric sparse LU",
                source,
            })
    }

    /// `x ← A⁻¹ x` with the last factorization.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            MatMut::from_column_major_slice_mut(x, self.dim, 1),
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
    }

    /// `y ← A x` with the current values.
    pub fn mul(&self, x: &[f64], y: &mut [f64]) {
        y.iter_mut().for_each(|v| *v = 0.0);
        for c in 0..self.dim {
            for k in self.col_ptr[c]..self.col_ptr[c + 1] {
                y[self.row_idx[k]] += self.values[k] * x[c];
            }
        }
    }

    /// Largest entry magnitude of the current values.
    pub fn max_abs(&self) -> f64 {
        self.values.iter().fold(0.0, |a, v| a.max(v.abs()))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 3 × 3 tridiagonal system with a known solution, refactored with new values through the
    /// same symbolic analysis.
    #[test]
    fn solves_and_refactors() {
        let entries = [(0, 0), (0, 1), (1, 0), (1, 1), (1, 2), (2, 1), (2, 2)];
        let mut lu = SparseLu::new(3, entries).unwrap();
        for scale in [1.0, 3.0] {
            for &(r, c) in &entries {
                let p = lu.position(r, c);
                lu.values_mut()[p] = if r == c { 4.0 * scale } else { -1.0 };
            }
            lu.factor().unwrap();
            let x = [1.0, -2.0, 0.5];
            let mut b = [0.0; 3];
            lu.mul(&x, &mut b);
            lu.solve_in_place(&mut b);
            for k in 0..3 {
                assert!((b[k] - x[k]).abs() < 1e-14);
            }
        }
    }
}
