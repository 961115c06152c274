//! Minimum-norm multipliers of redundant constraints, allocation-free after setup.
//!
//! A formulation that solved on a maximal independent set `R` of equations holds multipliers `λ_p`
//! (`λ_R` on `R`, zero on the dropped equations `D`). Every dropped row is a combination of the kept
//! ones, `C_dᵀ = C_Rᵀ α_d`, so the vectors `n_d = e_d − Σ_k α_dk e_{R_k}` span the null space of
//! `C_qᵀ`, and every `λ_p + N c` gives the same constraint force `C_qᵀ λ`. The minimum-norm one is
//!
//! ```text
//! λ = λ_p − N (NᵀN)⁻¹ Nᵀ λ_p,      α_d = (C_R C_Rᵀ)⁻¹ C_R C_dᵀ
//! ```
//!
//! (`docs/equations.md` §2: the reactions of a redundant set are not unique; this is the distribution
//! `docs/sign-conventions.md` reports). `C_R C_Rᵀ` is the sparse Gram matrix of the independent rows
//! ([`SparseGram`], symbolic analysis once), well conditioned because `R` is independent; the
//! near-null direction of the whole `C_q` never enters a factorization. The cost per evaluation is
//! one Gram factorization, one solve per dropped equation and a `|D| × |D|` Cholesky factorization.
//!
//! The dependence is checked on every call: `‖C_dᵀ − C_Rᵀ α_d‖∞ ≤` [`KEEP_DEPENDENCE`]` · ‖C_d‖∞`.
//! A row that no longer depends on the kept ones makes the call fail, and the caller analyses the
//! structure again.

use crate::gram::SparseGram;
use crate::linalg::small_ldlt;
use crate::{ConstraintPattern, ConstraintSet, ConstraintValues, DynamicsError};

/// Largest `‖C_dᵀ − C_Rᵀ α_d‖∞ / ‖C_d‖∞` for which a dropped row still counts as dependent on the
/// kept ones.
///
/// The redundancy is found at the rank tolerance
/// ([`crate::structure::MINIMUM_NORM_RANK_TOLERANCE`], 1e-6 of the largest singular value); off the
/// constraint manifold (the stages of an explicit method) the redundant direction of an
/// over-constrained loop opens further: up to 8.8e-7 on `scenes/bricard.toml` with dopri5 over 10 s
/// (5.5e-8 with RK4 at 1 ms), no margin below the rank tolerance. A first version cut there (with a
/// mass-weighted measure, which reached 2.0e-6) gave the set up at t = 0.72 s, and the structure
/// analysis at that off-manifold stage found the dropped row inconsistent and stopped the run.
/// The bound is kept tight above that (11× the largest measured) because a row dropped at a
/// *singular* position of a mechanism (not a structural redundancy) becomes independent again as
/// the mechanism moves on, and is not enforced while it counts as dependent; a row that stays
/// dependent within this bound loses nothing. Bricard with every integrator, and the redundant
/// parallelogram whirling through its flat positions (`scenes/redundant-parallelogram.toml` with
/// `angular_velocity = 8.0` on the first crank, RK4 at 1 ms, 3 s), give the same output at 1e-3
/// and 1e-5.
pub const KEEP_DEPENDENCE: f64 = 1e-5;

/// Why [`MinimumNorm::apply`] failed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum DependenceLost {
    /// The Gram matrix of the kept rows is not positive definite (they have become dependent).
    KeptRowsDependent,
    /// Dropped equation `row` is `defect` (relative) away from the span of the kept rows.
    RowIndependent {
        /// The system row.
        row: usize,
        /// `‖C_dᵀ − C_Rᵀ α_d‖∞ / ‖C_d‖∞`.
        defect: f64,
    },
}

/// The null space of `C_qᵀ` from the dropped equations of a redundant system, and the minimum-norm
/// multipliers (see the module documentation).
pub struct MinimumNorm {
    /// The kept equations `R`.
    rows: Vec<usize>,
    /// The dropped equations, each with its entries `(index in the values, column)`.
    dropped: Vec<(usize, Vec<(usize, usize)>)>,
    /// The pattern of `C_R`, and for each of its entries the index in the system's values.
    pattern: ConstraintPattern,
    entries: Vec<usize>,
    /// `C_R` (in `jacobian`; the other fields unused), loaded by [`MinimumNorm::load`].
    values: ConstraintValues,
    /// Row `k` of `C_R` as `(index in jacobian, column)`.
    row_entries: Vec<Vec<(usize, usize)>>,
    gram: SparseGram,
    /// `C_dᵀ` (`n_v`), `C_R C_dᵀ` then `α_d` (`|R|`).
    column: Vec<f64>,
    alpha: Vec<f64>,
    /// The null vectors, `|D|` of length `m` one after the other; `NᵀN` and `Nᵀ λ_p`.
    null: Vec<f64>,
    null_gram: Vec<f64>,
    c: Vec<f64>,
}

impl std::fmt::Debug for MinimumNorm {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("MinimumNorm")
            .field("rows", &self.rows.len())
            .field("dropped", &self.dropped.len())
            .finish()
    }
}

impl MinimumNorm {
    /// Storage and the Gram matrix's symbolic analysis for keeping equations `rows` of a system
    /// with constraint pattern `pattern`.
    pub fn new(pattern: &ConstraintPattern, rows: &[usize]) -> Result<Self, crate::gram::GramSingular> {
        let (n, m) = (pattern.cols(), pattern.rows());
        let (reduced, entries) = pattern.subset(rows);
        let mut kept = vec![false; m];
        rows.iter().for_each(|&r| kept[r] = true);
        let mut row_entries = vec![Vec::new(); rows.len()];
        for (e, &(r, c)) in reduced.entries().iter().enumerate() {
            row_entries[r].push((e, c));
        }
        let dropped = (0..m)
            .filter(|&row| !kept[row])
            .map(|row| {
                let e = pattern
                    .segments()
                    .iter()
                    .filter(|s| s.row == row)
                    .flat_map(|s| (0..s.len).map(move |k| (s.first + k, s.col + k)))
                    .collect();
                (row, e)
            })
            .collect::<Vec<_>>();
        let d = dropped.len();
        Ok(MinimumNorm {
            gram: SparseGram::on_pattern(&reduced)?,
            values: ConstraintValues::new(&reduced, 0),
            pattern: reduced,
            entries,
            row_entries,
            rows: rows.to_vec(),
            dropped,
            column: vec![0.0; n],
            alpha: vec![0.0; rows.len()],
            null: vec![0.0; d * m],
            null_gram: vec![0.0; d * d],
            c: vec![0.0; d],
        })
    }

    /// The kept equations.
    pub fn rows(&self) -> &[usize] {
        &self.rows
    }

    /// The pattern of `C_R` (row `k` is system row `rows()[k]`).
    pub fn pattern(&self) -> &ConstraintPattern {
        &self.pattern
    }

    /// `C_R` as last loaded (only `jacobian` is filled), for a formulation that factors the
    /// saddle-point matrix of the kept equations.
    pub fn values(&self) -> &ConstraintValues {
        &self.values
    }

    /// Copies `C_R` from the system's values.
    pub fn load(&mut self, values: &ConstraintValues) {
        for (v, &e) in self.values.jacobian.iter_mut().zip(&self.entries) {
            *v = values.jacobian[e];
        }
    }

    /// Replaces `lambda` (length `m`: the multipliers solved on the kept rows, anything on the
    /// dropped ones) by the minimum-norm multipliers of the same constraint force, from the
    /// Jacobian in `values`.
    pub fn apply(&mut self, values: &ConstraintValues, lambda: &mut [f64]) -> Result<(), DependenceLost> {
        self.load(values);
        self.apply_loaded(values, lambda)
    }

    /// [`MinimumNorm::apply`] with `C_R` already loaded from `values` ([`MinimumNorm::load`]).
    pub fn apply_loaded(&mut self, values: &ConstraintValues, lambda: &mut [f64]) -> Result<(), DependenceLost> {
        let m = lambda.len();
        let d = self.dropped.len();
        for &(row, _) in &self.dropped {
            lambda[row] = 0.0;
        }
        if d == 0 {
            return Ok(());
        }
        let unit = |_: usize, r: usize, c: usize| if r == c { 1.0 } else { 0.0 };
        if self.gram.factor(&self.values.jacobian, unit, 1e12).is_err() {
            return Err(DependenceLost::KeptRowsDependent);
        }
        for k in 0..d {
            let (row, entries) = &self.dropped[k];
            self.column.fill(0.0);
            let mut size = 0.0f64;
            for &(e, col) in entries {
                self.column[col] += values.jacobian[e];
                size = size.max(values.jacobian[e].abs());
            }
            // α = (C_R C_Rᵀ)⁻¹ C_R C_dᵀ.
            for (a, row_k) in self.alpha.iter_mut().zip(&self.row_entries) {
                *a = row_k
                    .iter()
                    .map(|&(e, c)| self.values.jacobian[e] * self.column[c])
                    .sum();
            }
            self.gram.solve_in_place(&mut self.alpha);
            // Defect C_dᵀ − C_Rᵀ α.
            for (a, row_k) in self.alpha.iter().zip(&self.row_entries) {
                for &(e, c) in row_k {
                    self.column[c] -= self.values.jacobian[e] * a;
                }
            }
            let defect = self.column.iter().fold(0.0f64, |a, v| a.max(v.abs())) / size.max(f64::MIN_POSITIVE);
            if defect.is_nan() || defect > KEEP_DEPENDENCE {
                return Err(DependenceLost::RowIndependent { row: *row, defect });
            }
            let nk = &mut self.null[k * m..(k + 1) * m];
            nk.fill(0.0);
            nk[*row] = 1.0;
            for (&kept, &a) in self.rows.iter().zip(&self.alpha) {
                nk[kept] = -a;
            }
        }
        // λ ← λ_p − N (NᵀN)⁻¹ Nᵀ λ_p; NᵀN is positive definite (each n_d has its 1 on its own row).
        let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
        for i in 0..d {
            let ni = &self.null[i * m..(i + 1) * m];
            self.c[i] = dot(ni, lambda);
            for j in 0..=i {
                self.null_gram[i * d + j] = dot(ni, &self.null[j * m..(j + 1) * m]);
            }
        }
        if small_ldlt::factor(&mut self.null_gram, d, 1.0, f64::EPSILON).is_err() {
            return Err(DependenceLost::KeptRowsDependent);
        }
        small_ldlt::solve(&self.null_gram, d, &mut self.c);
        for i in 0..d {
            for (l, v) in lambda.iter_mut().zip(&self.null[i * m..(i + 1) * m]) {
                *l -= self.c[i] * v;
            }
        }
        Ok(())
    }
}

/// Writes into `lambda` the multipliers `lam_rows` solved on the independent equations `rows` (zero
/// elsewhere) and, when `rows` leaves equations out, turns them into the minimum-norm multipliers
/// of the same constraint force with the [`MinimumNorm`] kept in `cache` (built again, allocating,
/// only when the row set changes). Where a dropped row no longer depends on the kept ones, falls
/// back to the truncated SVD of [`crate::structure::minimum_norm_multipliers`].
pub fn scatter_minimum_norm<S: ConstraintSet + ?Sized>(
    cache: &mut Option<MinimumNorm>,
    sys: &S,
    t: f64,
    values: &ConstraintValues,
    rows: &[usize],
    lam_rows: &[f64],
    lambda: &mut [f64],
) -> Result<(), DynamicsError> {
    crate::structure::scatter_rows(rows, lam_rows, lambda);
    if rows.len() == lambda.len() {
        return Ok(());
    }
    if cache.as_ref().is_none_or(|c| c.rows() != rows) {
        *cache = MinimumNorm::new(sys.pattern(), rows).ok();
    }
    let applied = cache.as_mut().is_some_and(|c| c.apply(values, lambda).is_ok());
    if applied {
        return Ok(());
    }
    sys.scatter_multipliers(t, values, rows, lam_rows, lambda)
}
