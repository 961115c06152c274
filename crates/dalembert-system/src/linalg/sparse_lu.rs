//! Sparse LU (faer) of a square matrix with a fixed pattern: the compressed-column structure, the
//! fill-reducing column order (COLAMD) and the scratch are built once; each [`SparseLu::factor`]
//! refactors the values numerically (partial pivoting by rows) without allocating once the factors
//! have reached their size.
//!
//! The factorization is faer's *simplicial* LU, called directly: its supernodal numeric
//! factorization (which faer picks by a flop-ratio heuristic for patterns with dense blocks)
//! allocates on every call in faer 0.24 (measured by `tests/allocation.rs`: 190 allocations per
//! factorization of a chain of 64 links' amalgamated matrix), and the simplicial factors give access
//! to the pivots, from which [`SparseLu::pivot_range`] reports the smallest and largest.

use super::rows::{row_axpy, union};
use super::LinalgError;
use crate::sparse_pattern::{compress_columns, entry_position};
use faer::dyn_stack::{MemBuffer, MemStack, StackReq};
use faer::perm::PermRef;
use faer::sparse::linalg::lu::simplicial::{self, SimplicialLu};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};

/// A square sparse matrix with a fixed pattern and its LU factors.
pub struct SparseLu {
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// The column order (COLAMD) of the symbolic analysis.
    symbolic: SymbolicLu<usize>,
    numeric: SimplicialLu<usize, f64>,
    row_perm: Vec<usize>,
    row_perm_inv: Vec<usize>,
    /// Whether `numeric` holds the factors of the current values.
    factored: bool,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    max_rhs: usize,
    /// Scratch of [`SparseLu::solve_rows`]: `dim × max_rhs` values and `dim` column ranges.
    rows_buf: Vec<f64>,
    rows_ranges: Vec<(usize, usize)>,
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
    /// its symbolic analysis, with scratch for solves of one right-hand side.
    pub fn new(dim: usize, entries: impl IntoIterator<Item = (usize, usize)>) -> Result<Self, LinalgError> {
        Self::with_right_hand_sides(dim, entries, 1)
    }

    /// As [`SparseLu::new`], with scratch for solving up to `max_rhs` right-hand sides at once
    /// ([`SparseLu::solve_columns`]).
    pub fn with_right_hand_sides(
        dim: usize,
        entries: impl IntoIterator<Item = (usize, usize)>,
        max_rhs: usize,
    ) -> Result<Self, LinalgError> {
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
        let max_rhs = max_rhs.max(1);
        let factor_buf = MemBuffer::new(simplicial::factorize_simplicial_numeric_lu_scratch::<usize, f64>(
            dim, dim,
        ));
        let solve_buf = MemBuffer::new(StackReq::any_of(&[
            simplicial::solve_in_place_scratch::<usize, f64>(dim, max_rhs, Par::Seq),
            simplicial::solve_transpose_in_place_scratch::<usize, f64>(dim, max_rhs, Par::Seq),
        ]));
        Ok(SparseLu {
            dim,
            values: vec![0.0; row_idx.len()],
            col_ptr,
            row_idx,
            symbolic,
            numeric: SimplicialLu::new(),
            row_perm: vec![0; dim],
            row_perm_inv: vec![0; dim],
            factored: false,
            factor_buf,
            solve_buf,
            max_rhs,
            rows_buf: vec![0.0; dim * max_rhs],
            rows_ranges: vec![(0, 0); dim],
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
        self.factored = false;
        &mut self.values
    }

    /// Numeric LU of the current values (symbolic analysis reused). Allocates nothing once the
    /// factors have reached their size. `Err` when a column has no non-zero pivot candidate.
    pub fn factor(&mut self) -> Result<(), LinalgError> {
        let s = SymbolicSparseColMatRef::new_checked(self.dim, self.dim, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(s, &self.values);
        self.factored = false;
        simplicial::factorize_simplicial_numeric_lu(
            &mut self.row_perm,
            &mut self.row_perm_inv,
            &mut self.numeric,
            a,
            self.symbolic.col_perm(),
            MemStack::new(&mut self.factor_buf),
        )
        .map_err(|source| LinalgError::SparseLu {
            what: "numeric sparse LU",
            source,
        })?;
        self.factored = true;
        Ok(())
    }

    /// Smallest and largest pivot magnitude of the last factorization (`(0, 0)` for an empty
    /// matrix, `(0, ∞)` when the last factorization failed): their ratio is a cheap condition
    /// estimate.
    pub fn pivot_range(&self) -> (f64, f64) {
        if !self.factored {
            return (0.0, f64::INFINITY);
        }
        let u = self.numeric.u_factor_unsorted();
        let (mut small, mut big) = (f64::INFINITY, 0.0f64);
        for j in 0..self.dim {
            // faer writes each column's pivot last (row index j).
            let p = u.val_of_col(j).last().map_or(0.0, |v| v.abs());
            small = small.min(p);
            big = big.max(p);
        }
        if self.dim == 0 {
            (0.0, 0.0)
        } else {
            (small, big)
        }
    }

    /// `X ← A⁻¹ X` for the columns of `x` (at most the `max_rhs` given at construction), with the
    /// last factorization.
    pub fn solve_columns(&mut self, x: MatMut<'_, f64>) {
        assert!(
            x.ncols() <= self.max_rhs,
            "more right-hand sides than the scratch was sized for"
        );
        self.numeric.solve_in_place_with_conj(
            PermRef::new_checked(&self.row_perm, &self.row_perm_inv, self.dim),
            self.symbolic.col_perm(),
            Conj::No,
            x,
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
    }

    /// `X ← A⁻¹ X` for `X` stored **by rows** (`dim × width`, row `i` at `x[i·width..]`, `width` at
    /// most the `max_rhs` given at construction), where `ranges[i]` bounds the columns in which row
    /// `i` may be non-zero (`(0, 0)` for an empty row). On return `ranges` bounds the rows of the
    /// solution. Each elimination step is an update of one row by another over the other's range,
    /// so right-hand sides that are zero in most columns cost little (on a chain, the dependent
    /// coordinates of link k depend only on the first k joints). Allocates nothing.
    pub fn solve_rows(&mut self, x: &mut [f64], width: usize, ranges: &mut [(usize, usize)]) {
        assert!(
            width <= self.max_rhs,
            "more right-hand sides than the scratch was sized for"
        );
        let n = self.dim;
        let y = &mut self.rows_buf[..n * width];
        let yr = &mut self.rows_ranges;
        // Y = P X (row i of Y is row row_perm[i] of X).
        for i in 0..n {
            let p = self.row_perm[i];
            yr[i] = ranges[p];
            let (lo, hi) = yr[i];
            let (row, src) = (&mut y[i * width..(i + 1) * width], &x[p * width..(p + 1) * width]);
            row[..lo].iter_mut().for_each(|v| *v = 0.0);
            row[lo..hi].copy_from_slice(&src[lo..hi]);
            row[hi..].iter_mut().for_each(|v| *v = 0.0);
        }
        let l = self.numeric.l_factor_unsorted();
        for j in 0..n {
            let (lo, hi) = yr[j];
            if lo >= hi {
                continue;
            }
            for (&i, &lij) in l.row_idx_of_col_raw(j).iter().zip(l.val_of_col(j)) {
                if i != j && lij != 0.0 {
                    row_axpy(y, width, i, j, -lij, lo, hi);
                    yr[i] = union(yr[i], (lo, hi));
                }
            }
        }
        let u = self.numeric.u_factor_unsorted();
        for j in (0..n).rev() {
            let (lo, hi) = yr[j];
            if lo >= hi {
                continue;
            }
            let (rows, vals) = (u.row_idx_of_col_raw(j), u.val_of_col(j));
            // faer writes each column's pivot last (row index j).
            let d = vals.last().copied().unwrap_or(0.0);
            y[j * width + lo..j * width + hi].iter_mut().for_each(|v| *v /= d);
            for (&i, &uij) in rows.iter().zip(vals) {
                if i != j && uij != 0.0 {
                    row_axpy(y, width, i, j, -uij, lo, hi);
                    yr[i] = union(yr[i], (lo, hi));
                }
            }
        }
        // X = Qᵀ Y (row i of X is row col_perm_inv[i] of Y).
        let (_, col_perm_inv) = self.symbolic.col_perm().arrays();
        for i in 0..n {
            let p = col_perm_inv[i];
            ranges[i] = yr[p];
            x[i * width..(i + 1) * width].copy_from_slice(&y[p * width..(p + 1) * width]);
        }
    }

    /// `x ← A⁻¹ x` with the last factorization.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        let n = self.dim;
        self.solve_columns(MatMut::from_column_major_slice_mut(x, n, 1));
    }

    /// `x ← A⁻ᵀ x` with the last factorization.
    pub fn solve_transpose_in_place(&mut self, x: &mut [f64]) {
        let n = self.dim;
        self.numeric.solve_transpose_in_place_with_conj(
            PermRef::new_checked(&self.row_perm, &self.row_perm_inv, self.dim),
            self.symbolic.col_perm(),
            Conj::No,
            MatMut::from_column_major_slice_mut(x, n, 1),
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
    /// same symbolic analysis; the transposed solve and the pivot range of a diagonal matrix.
    #[test]
    fn solves_and_refactors() {
        let entries = [(0, 0), (0, 1), (1, 0), (1, 1), (1, 2), (2, 1), (2, 2)];
        let mut lu = SparseLu::new(3, entries).unwrap();
        for scale in [1.0, 3.0] {
            for &(r, c) in &entries {
                let p = lu.position(r, c);
                lu.values_mut()[p] = if r == c { 4.0 * scale } else { -1.0 + (r as f64) * 0.5 };
            }
            lu.factor().unwrap();
            let x = [1.0, -2.0, 0.5];
            let mut b = [0.0; 3];
            lu.mul(&x, &mut b);
            lu.solve_in_place(&mut b);
            // Aᵀ x from the same values: y_c = Σ_r A_rc x_r.
            let mut bt = [0.0; 3];
            for &(r, c) in &entries {
                bt[c] += lu.values[lu.position(r, c)] * x[r];
            }
            lu.solve_transpose_in_place(&mut bt);
            for k in 0..3 {
                assert!((b[k] - x[k]).abs() < 1e-14 && (bt[k] - x[k]).abs() < 1e-14);
            }
        }
        let mut d = SparseLu::new(3, [(0, 0), (1, 1), (2, 2)]).unwrap();
        d.values_mut().copy_from_slice(&[2.0, -8.0, 0.5]);
        d.factor().unwrap();
        assert_eq!(d.pivot_range(), (0.5, 8.0));
    }
}
