//! Sparse range-space back end for large systems whose mass blocks are all positive definite:
//! `S = C_q M⁻¹ C_qᵀ` is assembled into a fixed sparse pattern (rows `i`, `j` couple when they share
//! a body, so `S` is banded for chains and trees) and factored by faer's sparse Cholesky, with the
//! ordering and symbolic analysis done once. Solves as the dense Schur back end:
//! `λ = S⁻¹ (C_q M⁻¹ b_top − b_bottom)`, `q̈ = M⁻¹ (b_top − C_qᵀ λ)`. Cost per evaluation is linear
//! in the number of bodies for chains.
//!
//! Singularity: a failed Cholesky, or a large amplification of a fixed pseudo-random probe vector
//! by `S⁻¹` (a rank-deficient `C_q` makes `S` singular). The assembly and factorization are
//! [`SparseGram`]'s, shared with the kinematic analysis.

use super::schur::InverseMass;
use super::SingularKkt;
use crate::gram::SparseGram;
use crate::{BlockDiagonal, ConstraintPattern, ConstraintValues};

pub(crate) struct SparseSchurKkt {
    n: usize,
    /// `S = C_q M⁻¹ C_qᵀ`: pattern, symbolic analysis (once), numeric Cholesky, condition probe.
    gram: SparseGram,
    minv: InverseMass,
    jacobian: Vec<f64>,
    tmp_n: Vec<f64>,
    tmp_m: Vec<f64>,
    pivot_tolerance: f64,
    /// Condition estimate from the probe: `‖S⁻¹ p‖∞ · max diag(S)`.
    pub condition: f64,
}

impl SparseSchurKkt {
    pub fn new(
        mass: &BlockDiagonal,
        mass_is_constant: bool,
        pattern: &ConstraintPattern,
        pivot_tolerance: f64,
    ) -> Result<Self, SingularKkt> {
        let (n, m) = (pattern.cols(), pattern.rows());
        let gram = SparseGram::on_pattern(pattern).map_err(|e| SingularKkt(e.0))?;
        Ok(SparseSchurKkt {
            n,
            gram,
            minv: InverseMass::new(mass, mass_is_constant),
            jacobian: vec![0.0; pattern.entries().len()],
            tmp_n: vec![0.0; n],
            tmp_m: vec![0.0; m],
            pivot_tolerance,
            condition: 1.0,
        })
    }

    pub fn factor(
        &mut self,
        mass: &BlockDiagonal,
        _pattern: &ConstraintPattern,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        self.minv.update(mass, false)?;
        let blocks = &self.minv.blocks;
        let result = self
            .gram
            .factor(
                &vals.jacobian,
                |b, r, c| blocks.get(b, r, c),
                1.0 / self.pivot_tolerance,
            )
            .map_err(|e| SingularKkt(format!("Schur complement: {}", e.0)));
        self.condition = self.gram.condition;
        result?;
        self.jacobian.copy_from_slice(&vals.jacobian);
        Ok(())
    }

    pub fn solve(&mut self, pattern: &ConstraintPattern, x: &mut [f64]) {
        let n = self.n;
        let (top, bottom) = x.split_at_mut(n);
        self.minv.apply(top, &mut self.tmp_n);
        self.tmp_m.iter_mut().for_each(|v| *v = 0.0);
        for (&(r, c), &v) in pattern.entries().iter().zip(&self.jacobian) {
            self.tmp_m[r] += v * self.tmp_n[c];
        }
        for (t, b) in self.tmp_m.iter_mut().zip(bottom.iter()) {
            *t -= b;
        }
        let mut lam = std::mem::take(&mut self.tmp_m);
        self.gram.solve_in_place(&mut lam);
        bottom.copy_from_slice(&lam);
        for (&(r, c), &v) in pattern.entries().iter().zip(&self.jacobian) {
            top[c] -= v * lam[r];
        }
        self.tmp_m = lam;
        self.minv.apply(top, &mut self.tmp_n);
        top.copy_from_slice(&self.tmp_n);
    }
}
