//! The sparse Gram matrix `G = C_q W C_qᵀ` (m × m) of the constraint Jacobian with a
//! block-diagonal weight `W` (one symmetric block per body, over its velocity coordinates), factored by faer's sparse
//! Cholesky with the symbolic analysis done once per pattern.
//!
//! Every entry of `G` couples two equations through a body they share, so `G` is banded for chains
//! and sparse for trees: the minimum-norm kinematic steps and the structure analysis of large
//! models (`crate::kinematics`, `crate::structure`) cost `O(nnz)`, not `O(n³)`.

use crate::ConstraintSet;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};

/// `G = C_q W C_qᵀ`: pattern, symbolic and numeric Cholesky, and its condition estimate.
pub struct SparseGram {
    m: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    l_values: Vec<f64>,
    /// `(body, block length, first entry of row i's segment, first entry of row j's segment,
    /// position of G_ij)`.
    contributions: Vec<(usize, usize, usize, usize, usize)>,
    symbolic: SymbolicCholesky<usize>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    probe: Vec<f64>,
    /// Estimated condition number of `G` after the last [`SparseGram::factor`]
    /// (`‖G⁻¹ p‖∞ · max diag G` for a fixed pseudo-random vector `p`, a lower bound).
    pub condition: f64,
}

/// `G` is not positive definite to working precision: `C_q` has lost rank (redundant constraints or
/// a singular position), or the symbolic analysis failed.
#[derive(Debug, Clone, PartialEq)]
pub struct GramSingular(pub String);

impl std::fmt::Debug for SparseGram {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SparseGram")
            .field("equations", &self.m)
            .field("entries", &self.values.len())
            .field("condition", &self.condition)
            .finish()
    }
}

impl SparseGram {
    /// The pattern of `G` for `sys` and its symbolic Cholesky analysis.
    pub fn new<S: ConstraintSet + ?Sized>(sys: &S) -> Result<Self, GramSingular> {
        Self::on_pattern(sys.pattern())
    }

    /// The pattern of `G` for the constraint pattern `pattern` and its symbolic Cholesky analysis.
    pub fn on_pattern(pattern: &crate::ConstraintPattern) -> Result<Self, GramSingular> {
        let m = pattern.rows();
        // Rows touching each body, with the first entry of their segment.
        let mut rows_of_body: Vec<Vec<(usize, usize)>> = vec![Vec::new(); pattern.bodies()];
        let mut len_of_body = vec![0; pattern.bodies()];
        for s in pattern.segments() {
            if s.len > crate::blocks::MAX_BLOCK {
                return Err(GramSingular(format!(
                    "a body with {} velocity coordinates (at most {} supported)",
                    s.len,
                    crate::blocks::MAX_BLOCK
                )));
            }
            rows_of_body[s.body].push((s.row, s.first));
            len_of_body[s.body] = s.len;
        }
        let mut cols: Vec<Vec<usize>> = (0..m).map(|i| vec![i]).collect();
        for rows in &rows_of_body {
            for &(i, _) in rows {
                for &(j, _) in rows {
                    if i > j {
                        cols[j].push(i);
                    }
                }
            }
        }
        let (col_ptr, row_idx) = crate::sparse_pattern::compress_columns(cols);
        let pos = |i: usize, j: usize| crate::sparse_pattern::entry_position(&col_ptr, &row_idx, i, j);
        let mut contributions = Vec::new();
        for (b, rows) in rows_of_body.iter().enumerate() {
            for &(i, ei) in rows {
                for &(j, ej) in rows {
                    if i >= j {
                        contributions.push((b, len_of_body[b], ei, ej, pos(i, j)));
                    }
                }
            }
        }
        let symbolic = {
            let s = SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &row_idx);
            factorize_symbolic_cholesky(s, Side::Lower, Default::default(), Default::default())
                .map_err(|e| GramSingular(format!("symbolic Cholesky of C_q W C_qᵀ: {e:?}")))?
        };
        let factor_buf = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
        let solve_buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        Ok(SparseGram {
            m,
            values: vec![0.0; row_idx.len()],
            l_values: vec![0.0; symbolic.len_val()],
            col_ptr,
            row_idx,
            contributions,
            symbolic,
            factor_buf,
            solve_buf,
            probe: vec![0.0; m],
            condition: 1.0,
        })
    }

    /// Assembles `G = C_q W C_qᵀ` from the Jacobian values (in the order of
    /// [`ConstraintSet::pattern`]) and `weight(body, r, c)` (entry `(r, c)` of body `body`'s block of
    /// `W`), and factors it. Fails when `G` is not
    /// positive definite or its estimated condition number exceeds `max_condition`.
    pub fn factor(
        &mut self,
        jacobian: &[f64],
        weight: impl Fn(usize, usize, usize) -> f64,
        max_condition: f64,
    ) -> Result<(), GramSingular> {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        // Contributions come grouped by (body, row i): w_i = W_b C_i,bᵀ once per group.
        let mut current = (usize::MAX, usize::MAX);
        let mut wi = [0.0; crate::blocks::MAX_BLOCK];
        for &(b, len, ei, ej, p) in &self.contributions {
            if current != (b, ei) {
                current = (b, ei);
                for (r, w) in wi.iter_mut().enumerate().take(len) {
                    *w = (0..len).map(|c| weight(b, r, c) * jacobian[ei + c]).sum();
                }
            }
            self.values[p] += if len == 3 {
                // Planar bodies: the unrolled product.
                wi[0] * jacobian[ej] + wi[1] * jacobian[ej + 1] + wi[2] * jacobian[ej + 2]
            } else {
                (0..len).map(|r| wi[r] * jacobian[ej + r]).sum::<f64>()
            };
        }
        let s = SymbolicSparseColMatRef::new_checked(self.m, self.m, &self.col_ptr, None, &self.row_idx);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                SparseColMatRef::new(s, &self.values),
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.factor_buf),
                Default::default(),
            )
            .map_err(|e| GramSingular(format!("sparse Cholesky of C_q W C_qᵀ: {e:?}")))?;
        // Condition probe: ‖G⁻¹ p‖∞ · max diag G for a fixed pseudo-random p with entries in
        // [−1, 1]. Its entries are all distinct, so p is not orthogonal to the null vector of two
        // duplicated equations (e_i − e_j), as a ±1 pattern can be.
        let mut probe = std::mem::take(&mut self.probe);
        for (i, p) in probe.iter_mut().enumerate() {
            *p = unit_hash(i as u64);
        }
        self.solve_in_place(&mut probe);
        let largest = (0..self.m).map(|j| self.values[self.col_ptr[j]]).fold(0.0f64, f64::max);
        self.condition = probe.iter().fold(0.0f64, |a, v| a.max(v.abs())) * largest;
        self.probe = probe;
        if !(self.condition.is_finite() && self.condition <= max_condition) {
            return Err(GramSingular(format!(
                "C_q W C_qᵀ: estimated condition number {:.3e}",
                self.condition
            )));
        }
        Ok(())
    }

    /// `x ← G⁻¹ x` with the last factorization.
    pub fn solve_in_place(&mut self, x: &mut [f64]) {
        let rhs = MatMut::from_column_major_slice_mut(x, self.m, 1);
        LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
    }
}

/// A deterministic pseudo-random number in [−1, 1) from `i` (splitmix64).
fn unit_hash(i: u64) -> f64 {
    let mut z = i.wrapping_add(0x9E37_79B9_7F4A_7C15);
    z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
    z ^= z >> 31;
    (z >> 11) as f64 / (1u64 << 52) as f64 - 1.0
}
