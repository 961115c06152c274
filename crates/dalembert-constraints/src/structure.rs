//! Structure analysis: rank of `C_q`, degrees of freedom, redundant equations.
//!
//! The rank comes from an LU factorization with full pivoting of `C_qᵀ` (n × m): its pivot
//! columns are a maximal independent set of constraint rows; the other rows are **redundant**
//! (linear combinations of the chosen ones at this configuration). A pivot counts as non-zero when
//! it exceeds `rank_tolerance × |largest pivot|`. Degrees of freedom: `n − rank`.
//!
//! Large models ([`SPARSE_FROM`] coordinates or more) are first tested for full row rank by a
//! sparse Cholesky of `C_q C_qᵀ` with a condition estimate ([`SparseGram`]): if the estimate is at
//! most `1 / rank_tolerance`, every equation is independent and no dense matrix is formed. Otherwise the dense analysis runs when it
//! fits in [`DENSE_LIMIT_BYTES`], and the result is [`ConstraintError::TooLarge`] when it does not.

use crate::gram::SparseGram;
use crate::{ConstraintError, ConstraintSystem, ConstraintValues, EquationRef};

/// From this many coordinates on, the analyses try the sparse path first ([`SparseGram`]): the
/// dense `O(n³)` factorizations take seconds from about 2000 coordinates on.
pub const SPARSE_FROM: usize = 600;

/// Largest dense matrix the analyses allocate: 1 GiB.
pub const DENSE_LIMIT_BYTES: usize = 1 << 30;

/// Why a large model reached a dense analysis, and what it needs.
pub(crate) const RANK_DEFICIENT_HINT: &str =
    "models this large are analysed only when their constraints are independent (no redundant equations, no singular position)";

/// True when a dense `rows × cols` matrix of `f64` stays within [`DENSE_LIMIT_BYTES`].
pub fn dense_fits(rows: usize, cols: usize) -> bool {
    rows.checked_mul(cols)
        .and_then(|e| e.checked_mul(8))
        .is_some_and(|b| b <= DENSE_LIMIT_BYTES)
}

/// The outcome of a structure analysis at one configuration.
#[derive(Debug, Clone, PartialEq)]
pub struct StructureReport {
    /// Number of coordinates `n`.
    pub coordinates: usize,
    /// Number of constraint equations `m`.
    pub equations: usize,
    /// Numerical rank of `C_q`.
    pub rank: usize,
    /// Degrees of freedom `n − rank`.
    pub degrees_of_freedom: usize,
    /// System rows of a maximal independent set of equations, ascending.
    pub independent_rows: Vec<usize>,
    /// The equations left out of that set (redundant at this configuration), by name.
    pub redundant: Vec<EquationRef>,
}

impl StructureReport {
    /// True when every equation is independent.
    pub fn is_full_rank(&self) -> bool {
        self.rank == self.equations
    }
}

/// Numerical rank and pivot order of a dense matrix's columns (full-pivot LU): the first `rank`
/// entries of the returned order are independent columns.
pub fn column_rank(a: faer::MatRef<'_, f64>, rank_tolerance: f64) -> (usize, Vec<usize>) {
    if a.nrows() == 0 || a.ncols() == 0 {
        return (0, (0..a.ncols()).collect());
    }
    let lu = a.full_piv_lu();
    let u = lu.U();
    let k = u.nrows().min(u.ncols());
    let largest = (0..k).map(|i| u[(i, i)].abs()).fold(0.0, f64::max);
    let rank = if largest == 0.0 || !largest.is_finite() {
        0
    } else {
        (0..k)
            .take_while(|&i| u[(i, i)].abs() > rank_tolerance * largest)
            .count()
    };
    let order: Vec<usize> = lu.Q().arrays().0.to_vec();
    (rank, order)
}

impl ConstraintSystem {
    /// Rank, degrees of freedom and redundant equations of `C_q` held in `values`.
    pub fn analyse_structure(
        &self,
        values: &ConstraintValues,
        rank_tolerance: f64,
    ) -> Result<StructureReport, ConstraintError> {
        let n = self.num_coordinates();
        let m = self.num_equations();
        if n >= SPARSE_FROM && self.has_full_row_rank_sparse(values, rank_tolerance) {
            return Ok(StructureReport {
                coordinates: n,
                equations: m,
                rank: m,
                degrees_of_freedom: n - m,
                independent_rows: (0..m).collect(),
                redundant: Vec::new(),
            });
        }
        if !dense_fits(n, m) {
            return Err(ConstraintError::TooLarge {
                what: "structure analysis".into(),
                hint: RANK_DEFICIENT_HINT,
                rows: n,
                cols: m,
            });
        }
        let jt = self.jacobian_dense(values).transpose().to_owned();
        let (rank, order) = column_rank(jt.as_ref(), rank_tolerance);
        let mut independent_rows: Vec<usize> = order[..rank].to_vec();
        independent_rows.sort_unstable();
        let mut redundant_rows: Vec<usize> = order[rank..].to_vec();
        redundant_rows.sort_unstable();
        Ok(StructureReport {
            coordinates: n,
            equations: m,
            rank,
            degrees_of_freedom: n - rank,
            independent_rows,
            redundant: redundant_rows.into_iter().map(|r| self.equation(r)).collect(),
        })
    }

    /// True when a sparse Cholesky of `C_q C_qᵀ` succeeds with an estimated condition number of at
    /// most `1 / rank_tolerance`: then `C_q` has full row rank by a wide margin. (A duplicated
    /// equation gives about 1e15 to 1e16 in floating point, never the exact infinity; chains of 300
    /// to 100 000 links give 50 to 100.) Anything in between is left to the dense analysis.
    fn has_full_row_rank_sparse(&self, values: &ConstraintValues, rank_tolerance: f64) -> bool {
        let Ok(mut gram) = SparseGram::new(self) else {
            return false;
        };
        gram.factor(
            &values.jacobian,
            |_| nalgebra::Matrix3::identity(),
            1.0 / rank_tolerance,
        )
        .is_ok()
    }

    /// Equations involved in a rank loss: the rows with a significant component in the left null
    /// space of `C_q` (from an SVD; systems above 600 equations fall back to the redundant set of
    /// [`ConstraintSystem::analyse_structure`], and to none when that analysis is too large).
    pub fn dependent_equations(&self, values: &ConstraintValues, rank_tolerance: f64) -> Vec<EquationRef> {
        let m = self.num_equations();
        let redundant = || {
            self.analyse_structure(values, rank_tolerance)
                .map(|s| s.redundant)
                .unwrap_or_default()
        };
        if m > 600 {
            return redundant();
        }
        let a = self.jacobian_dense(values);
        let Ok(svd) = a.svd() else {
            return redundant();
        };
        let s = svd.S().column_vector();
        let largest = (0..s.nrows()).map(|i| s[i]).fold(0.0, f64::max);
        let rank = (0..s.nrows()).filter(|&i| s[i] > rank_tolerance * largest).count();
        let u = svd.U();
        (0..m)
            .filter(|&r| (rank..m).any(|j| u[(r, j)].abs() > 1e-6))
            .map(|r| self.equation(r))
            .collect()
    }
}
