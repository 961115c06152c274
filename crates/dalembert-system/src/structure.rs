//! Structure analysis: rank of `C_q`, degrees of freedom, redundant equations.
//!
//! The rank comes from an LU factorization with full pivoting of `C_qᵀ` (n × m): its pivot
//! columns are a maximal independent set of constraint rows; the other rows are **redundant**
//! (linear combinations of the chosen ones at this configuration). A pivot counts as non-zero when
//! it exceeds `rank_tolerance × |largest pivot|`. Degrees of freedom: `n − rank`.
//!
//! Large models ([`SPARSE_RANK_FROM`] coordinates or more) are first tested for full row rank by a
//! sparse Cholesky of `C_q C_qᵀ` with a condition estimate ([`SparseGram`]): if the estimate is at
//! most `1 / rank_tolerance`, every equation is independent and no dense matrix is formed. Otherwise the dense analysis runs when it
//! fits in [`DENSE_LIMIT_BYTES`], and the result is [`ConstraintError::TooLarge`] when it does not.

use crate::gram::SparseGram;
use crate::jacobian_svd::{nearly_singular_range, JacobianSvd, SVD_EQUATIONS_UP_TO};
use crate::{ConstraintError, ConstraintSet, ConstraintValues, EquationRef};

/// From this many coordinates on, the analyses try the sparse path first ([`SparseGram`]): the
/// dense `O(n³)` factorizations take seconds from about 2000 coordinates on.
pub const SPARSE_FROM: usize = 600;

/// From this many coordinates on, [`analyse_structure`] tries the sparse full-rank test first: on
/// a spatial chain of 64 links (384 coordinates, 320 equations) it takes 0.3 ms where the dense
/// pivoting and singular values take 26 ms. It passes only where the condition number of
/// `C_q C_qᵀ` is estimated at most `1 / tolerance` (singular values of `C_q` within a factor
/// `tolerance^(−1/2)`), where the dense analysis counts a rank loss only below `tolerance` times the
/// largest singular value; anything else goes to the dense analysis.
pub const SPARSE_RANK_FROM: usize = 100;

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
    let mut lu = a.to_owned();
    let mut pivot = crate::linalg::FullPivot::new(a.nrows(), a.ncols());
    let rank = pivot.rank(lu.as_mut(), rank_tolerance);
    (rank, pivot.order(a.ncols()).to_vec())
}

/// Most equations for which [`analyse_structure`] confirms the rank by singular values.
const SVD_RANK_UP_TO: usize = 600;

/// Rank, degrees of freedom and redundant equations of `C_q` held in `values`: the numerical rank
/// counts singular values above `rank_tolerance × σ_max` (LU pivots beyond 600 equations); the
/// independent rows are the first `rank` of a full-pivot LU of `C_qᵀ`.
pub fn analyse_structure<S: ConstraintSet + ?Sized>(
    sys: &S,
    values: &ConstraintValues,
    rank_tolerance: f64,
) -> Result<StructureReport, ConstraintError> {
    let n = sys.num_coordinates();
    let m = sys.num_equations();
    if n >= SPARSE_RANK_FROM && has_full_row_rank_sparse(sys, values, rank_tolerance) {
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
    let jt = sys.jacobian_dense(values).transpose().to_owned();
    let (pivot_rank, order) = column_rank(jt.as_ref(), rank_tolerance);
    // LU pivots can overstate the rank: off the constraint manifold (|C| ~ 1e-10 after a
    // projected step) an over-constrained loop such as Bricard's has one singular value of about
    // 1e-10 that a pivot test may count (measured on scenes/bricard.toml). The singular values
    // decide where they are affordable; the pivot order still picks the independent rows.
    let rank = if m <= SVD_RANK_UP_TO {
        let s = jt.singular_values().unwrap_or_default();
        let largest = s.iter().cloned().fold(0.0, f64::max);
        pivot_rank.min(s.iter().filter(|&&v| v > rank_tolerance * largest).count())
    } else {
        pivot_rank
    };
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
        redundant: redundant_rows.into_iter().map(|r| sys.equation(r)).collect(),
    })
}

/// True when a sparse Cholesky of `C_q C_qᵀ` succeeds with an estimated condition number of at
/// most `1 / rank_tolerance`: then `C_q` has full row rank by a wide margin. (A duplicated
/// equation gives about 1e15 to 1e16 in floating point, never the exact infinity; chains of 300
/// to 100 000 links give 50 to 100.) Anything in between is left to the dense analysis.
fn has_full_row_rank_sparse<S: ConstraintSet + ?Sized>(
    sys: &S,
    values: &ConstraintValues,
    rank_tolerance: f64,
) -> bool {
    let Ok(mut gram) = SparseGram::new(sys) else {
        return false;
    };
    gram.factor(&values.jacobian, |_, r, c| f64::from(r == c), 1.0 / rank_tolerance)
        .is_ok()
}

/// Equations involved in a rank loss: the rows with a significant component in the left null
/// space of `C_q` (from an SVD; systems above 600 equations fall back to the redundant set of
/// [`analyse_structure`], and to none when that analysis is too large).
pub fn dependent_equations<S: ConstraintSet + ?Sized>(
    sys: &S,
    values: &ConstraintValues,
    rank_tolerance: f64,
) -> Vec<EquationRef> {
    let m = sys.num_equations();
    let redundant = || {
        analyse_structure(sys, values, rank_tolerance)
            .map(|s| s.redundant)
            .unwrap_or_default()
    };
    if m > SVD_EQUATIONS_UP_TO {
        return redundant();
    }
    singular_vector_rows(sys, values, 1e-6, |s, largest| {
        // The caller found `C_q` rank deficient (by its own pivoting); where the singular values
        // all clear the tolerance, the weakest direction is the one that failed (seen on Bricard's
        // loop with dopri5: "rank 29 of 30" with no equation named).
        let rank = s.iter().filter(|&&v| v > rank_tolerance * largest).count();
        Some((rank.min(m.saturating_sub(1)), m))
    })
    .unwrap_or_else(redundant)
}

/// The equations with weight above `weight` in the left singular vectors `from..to` of the dense
/// `C_q`, the range chosen by `select(singular values, largest)`; `None` when the SVD fails or
/// `select` declines.
fn singular_vector_rows<S: ConstraintSet + ?Sized>(
    sys: &S,
    values: &ConstraintValues,
    weight: f64,
    select: impl Fn(&[f64], f64) -> Option<(usize, usize)>,
) -> Option<Vec<EquationRef>> {
    let mut svd = JacobianSvd::new(sys.num_equations(), sys.num_coordinates());
    if !svd.decompose(sys, values) {
        return None;
    }
    svd.rows_of_vectors(sys, weight, select)
}

/// The equations of a **nearly** singular `C_q` (a closed chain close to a singular position, where
/// links line up): `Some` when the singular values above `rank_tolerance × σ_max` (the numerical
/// rank, which redundant constraints lower permanently) include some below `near_tolerance × σ_max`;
/// the equations returned are those with weight in the left singular vectors of those values.
/// `None` for a well-conditioned `C_q` and for more than [`SVD_EQUATIONS_UP_TO`] equations (not
/// checked). Allocates its storage; a run checking while it steps keeps a
/// [`crate::jacobian_svd::SingularityCheck`] instead.
pub fn near_singular<S: ConstraintSet + ?Sized>(
    sys: &S,
    values: &ConstraintValues,
    near_tolerance: f64,
    rank_tolerance: f64,
) -> Option<Vec<EquationRef>> {
    let m = sys.num_equations();
    if m == 0 || m > SVD_EQUATIONS_UP_TO {
        return None;
    }
    singular_vector_rows(sys, values, 1e-3, |s, largest| {
        nearly_singular_range(s, largest, near_tolerance, rank_tolerance)
    })
}

/// The error for a rank-deficient `C_q` at `values`: rank, and the equations in the dependent set.
pub fn redundancy_error<S: ConstraintSet + ?Sized>(sys: &S, t: f64, values: &ConstraintValues) -> crate::DynamicsError {
    let s = match analyse_structure(sys, values, 1e-9) {
        Ok(s) => s,
        Err(e) => return e.into(),
    };
    crate::DynamicsError::RedundantConstraints {
        time: t,
        rank: s.rank,
        equations: s.equations,
        involved: dependent_equations(sys, values, 1e-9),
    }
}

/// `lambda[rows[k]] = lam_rows[k]`, zero elsewhere.
pub fn scatter_rows(rows: &[usize], lam_rows: &[f64], lambda: &mut [f64]) {
    lambda.iter_mut().for_each(|l| *l = 0.0);
    for (&row, &l) in rows.iter().zip(lam_rows) {
        lambda[row] = l;
    }
}

/// Writes multipliers `lam_rows` solved on the independent `rows` into `lambda` (zero elsewhere);
/// when some rows were left out (redundant constraints), replaces them by the minimum-norm
/// multipliers of the same generalized constraint force `C_qᵀ λ`.
pub fn scatter_multipliers<S: ConstraintSet + ?Sized>(
    sys: &S,
    t: f64,
    values: &ConstraintValues,
    rows: &[usize],
    lam_rows: &[f64],
    lambda: &mut [f64],
) -> Result<(), crate::DynamicsError> {
    scatter_rows(rows, lam_rows, lambda);
    if rows.len() < sys.num_equations() {
        let mut f = vec![0.0; sys.num_coordinates()];
        sys.jacobian_transpose_mul_add(values, 1.0, lambda, &mut f);
        let mn = minimum_norm_multipliers(sys, values, &f).ok_or(crate::DynamicsError::Factorization {
            time: t,
            what: "minimum-norm multipliers: the constraint force is not in the range of C_qᵀ".into(),
        })?;
        lambda.copy_from_slice(&mn);
    }
    Ok(())
}

/// Relative singular value below which the minimum-norm treatment counts a direction of `C_q` as
/// redundant. Looser than the `1e-9` of structure reports: a run with redundant constraints leaves
/// the constraint manifold by the projection tolerance (~1e-10), and an over-constrained loop's
/// redundant direction then has a singular value of 1e-10 … 2e-9 of the largest (measured on
/// `scenes/bricard.toml`), which must still count as redundant.
pub const MINIMUM_NORM_RANK_TOLERANCE: f64 = 1e-6;

/// The minimum-norm multipliers `λ = (C_qᵀ)⁺ f` for a generalized constraint force `f` in the
/// range of `C_qᵀ` (for redundant constraints, one admissible distribution of the reactions).
///
/// With the SVD `C_q = U Σ Vᵀ`, `λ = Σ_k u_k (v_kᵀ f) / σ_k` over the singular values above
/// [`MINIMUM_NORM_RANK_TOLERANCE`]` × σ_max`. The cut is on singular values, not
/// on LU pivots: off the constraint manifold (a projected step leaves `|C| ~ 1e-10`) an
/// over-constrained loop such as Bricard's has a singular value of that size, which a pivot test
/// can count as independent and a Gram matrix `C_qᵀC_q` then squares to ~1e-20 (measured:
/// `scenes/bricard.toml` stopped at t = 0.0275 s). Dense; allocates (a fallback path for
/// redundant constraints). `None` when `f` is not in the range of `C_qᵀ` (reproduced to 1e-8 of
/// its size, plus what the directions cut off may carry).
pub fn minimum_norm_multipliers<S: ConstraintSet + ?Sized>(
    sys: &S,
    values: &ConstraintValues,
    f: &[f64],
) -> Option<Vec<f64>> {
    let a = sys.jacobian_dense(values);
    let (m, n) = (a.nrows(), a.ncols());
    let svd = a.thin_svd().ok()?;
    let sigma = svd.S().column_vector();
    let (u, v) = (svd.U(), svd.V());
    let largest = (0..sigma.nrows()).map(|k| sigma[k]).fold(0.0, f64::max);
    let mut lam = vec![0.0; m];
    for k in 0..sigma.nrows() {
        if sigma[k] <= MINIMUM_NORM_RANK_TOLERANCE * largest {
            continue;
        }
        let c = (0..n).map(|j| v[(j, k)] * f[j]).sum::<f64>() / sigma[k];
        for (i, l) in lam.iter_mut().enumerate() {
            *l += u[(i, k)] * c;
        }
    }
    // f must be reproduced on every coordinate.
    let mut back = vec![0.0; n];
    sys.jacobian_transpose_mul_add(values, 1.0, &lam, &mut back);
    // What the dropped directions may carry: f's part along them is σ_k (u_kᵀ λ) with
    // σ_k ≤ MINIMUM_NORM_RANK_TOLERANCE σ_max.
    let lam_size = lam.iter().fold(0.0f64, |s, v| s.max(v.abs()));
    let tolerance = 1e-8 * f.iter().fold(1.0f64, |s, v| s.max(v.abs()))
        + MINIMUM_NORM_RANK_TOLERANCE * largest * lam_size * (m as f64).sqrt();
    let ok = lam.iter().all(|l| l.is_finite()) && back.iter().zip(f).all(|(b, fi)| (b - fi).abs() <= tolerance);
    ok.then_some(lam)
}
