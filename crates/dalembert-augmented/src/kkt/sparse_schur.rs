//! Sparse range-space back end for large systems whose mass blocks are all positive definite:
//! `S = C_q M⁻¹ C_qᵀ` is assembled into a fixed sparse pattern (rows `i`, `j` couple when they share
//! a body, so `S` is banded for chains and trees) and factored by faer's sparse Cholesky, with the
//! ordering and symbolic analysis done once. Solves as the dense Schur back end:
//! `λ = S⁻¹ (C_q M⁻¹ b_top − b_bottom)`, `q̈ = M⁻¹ (b_top − C_qᵀ λ)`. Cost per evaluation is linear
//! in the number of bodies for chains.
//!
//! Singularity: a failed Cholesky, or a large amplification of a fixed ±1 probe vector by `S⁻¹`
//! (a rank-deficient `C_q` makes `S` singular).

use super::schur::InverseMass;
use super::SingularKkt;
use dalembert_constraints::{ConstraintSystem, ConstraintValues};
use dalembert_kinematics::MassMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::LltRegularization;
use faer::sparse::linalg::cholesky::{factorize_symbolic_cholesky, LltRef, SymbolicCholesky};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par, Side};
use nalgebra::Vector3;

pub(crate) struct SparseSchurKkt {
    n: usize,
    m: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// `(body, first entry of row i on the body, first entry of row j, position in values)`.
    contributions: Vec<(usize, usize, usize, usize)>,
    symbolic: SymbolicCholesky<usize>,
    l_values: Vec<f64>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    minv: InverseMass,
    jacobian: Vec<f64>,
    tmp_n: Vec<f64>,
    tmp_m: Vec<f64>,
    probe: Vec<f64>,
    pivot_tolerance: f64,
    /// Condition estimate from the probe: `‖S⁻¹ p‖∞ · max diag(S)`.
    pub condition: f64,
}

impl SparseSchurKkt {
    pub fn new(sys: &ConstraintSystem, pivot_tolerance: f64) -> Result<Self, SingularKkt> {
        let n = sys.num_coordinates();
        let m = sys.num_equations();
        let mut rows_of_body: Vec<Vec<(usize, usize)>> = vec![Vec::new(); n / 3];
        for (e, &(r, c)) in sys.pattern().iter().enumerate() {
            if c % 3 == 0 {
                rows_of_body[c / 3].push((r, e));
            }
        }
        // Lower-triangle pattern of S (diagonal included).
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); m];
        for i in 0..m {
            cols[i].push(i);
        }
        for rows in &rows_of_body {
            for &(i, _) in rows {
                for &(j, _) in rows {
                    if i > j {
                        cols[j].push(i);
                    }
                }
            }
        }
        let (col_ptr, row_idx) = dalembert_constraints::sparse_pattern::compress_columns(cols);
        let pos = |i: usize, j: usize| dalembert_constraints::sparse_pattern::entry_position(&col_ptr, &row_idx, i, j);
        let mut contributions = Vec::new();
        for (b, rows) in rows_of_body.iter().enumerate() {
            for &(i, ei) in rows {
                for &(j, ej) in rows {
                    if i >= j {
                        contributions.push((b, ei, ej, pos(i, j)));
                    }
                }
            }
        }
        let symbolic = {
            let s = SymbolicSparseColMatRef::new_checked(m, m, &col_ptr, None, &row_idx);
            factorize_symbolic_cholesky(s, Side::Lower, Default::default(), Default::default())
                .map_err(|e| SingularKkt(format!("symbolic Cholesky: {e:?}")))?
        };
        let factor_buf = MemBuffer::new(symbolic.factorize_numeric_llt_scratch::<f64>(Par::Seq, Default::default()));
        let solve_buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        Ok(SparseSchurKkt {
            n,
            m,
            values: vec![0.0; row_idx.len()],
            l_values: vec![0.0; symbolic.len_val()],
            col_ptr,
            row_idx,
            contributions,
            symbolic,
            factor_buf,
            solve_buf,
            minv: InverseMass::new(n / 3),
            jacobian: vec![0.0; sys.pattern().len()],
            tmp_n: vec![0.0; n],
            tmp_m: vec![0.0; m],
            probe: vec![0.0; m],
            pivot_tolerance,
            condition: 1.0,
        })
    }

    pub fn factor(
        &mut self,
        mass: &MassMatrix,
        _sys: &ConstraintSystem,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        self.minv.update(mass, false)?;
        let jac = &vals.jacobian;
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for &(b, ei, ej, p) in &self.contributions {
            let wi = self.minv.blocks[b] * Vector3::new(jac[ei], jac[ei + 1], jac[ei + 2]);
            self.values[p] += wi.x * jac[ej] + wi.y * jac[ej + 1] + wi.z * jac[ej + 2];
        }
        let s = SymbolicSparseColMatRef::new_checked(self.m, self.m, &self.col_ptr, None, &self.row_idx);
        let a = SparseColMatRef::new(s, &self.values);
        self.symbolic
            .factorize_numeric_llt(
                &mut self.l_values,
                a,
                Side::Lower,
                LltRegularization::default(),
                Par::Seq,
                MemStack::new(&mut self.factor_buf),
                Default::default(),
            )
            .map_err(|e| SingularKkt(format!("sparse Cholesky of the Schur complement: {e:?}")))?;
        self.jacobian.copy_from_slice(jac);
        // Singularity probe: ‖S⁻¹ p‖ · max diag(S) for a fixed ±1 vector p.
        for (i, p) in self.probe.iter_mut().enumerate() {
            *p = if (i * 7 + 3) % 5 < 2 { -1.0 } else { 1.0 };
        }
        let mut probe = std::mem::take(&mut self.probe);
        self.solve_s(&mut probe);
        let largest = (0..self.m).map(|j| self.values[self.col_ptr[j]]).fold(0.0f64, f64::max);
        let growth = probe.iter().fold(0.0f64, |a, v| a.max(v.abs())) * largest;
        self.probe = probe;
        self.condition = growth;
        let regular = growth.is_finite() && growth * self.pivot_tolerance < 1.0;
        if !regular {
            return Err(SingularKkt(format!(
                "Schur complement: estimated condition number {growth:.3e}"
            )));
        }
        Ok(())
    }

    fn solve_s(&mut self, x: &mut [f64]) {
        let rhs = MatMut::from_column_major_slice_mut(x, self.m, 1);
        LltRef::new(&self.symbolic, &self.l_values).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
    }

    pub fn solve(&mut self, sys: &ConstraintSystem, x: &mut [f64]) {
        let n = self.n;
        let (top, bottom) = x.split_at_mut(n);
        self.minv.apply(top, &mut self.tmp_n);
        self.tmp_m.iter_mut().for_each(|v| *v = 0.0);
        for (&(r, c), &v) in sys.pattern().iter().zip(&self.jacobian) {
            self.tmp_m[r] += v * self.tmp_n[c];
        }
        for (t, b) in self.tmp_m.iter_mut().zip(bottom.iter()) {
            *t -= b;
        }
        let mut lam = std::mem::take(&mut self.tmp_m);
        self.solve_s(&mut lam);
        bottom.copy_from_slice(&lam);
        for (&(r, c), &v) in sys.pattern().iter().zip(&self.jacobian) {
            top[c] -= v * lam[r];
        }
        self.tmp_m = lam;
        self.minv.apply(top, &mut self.tmp_n);
        top.copy_from_slice(&self.tmp_n);
    }
}
