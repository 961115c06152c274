//! Sparse back end: faer's sparse LU. The pattern of `[M C_qᵀ; C_q 0]` and its symbolic analysis
//! are computed once; each evaluation scatters the new values through a precomputed map and
//! refactors numerically into reused storage and scratch.

use super::SingularKkt;
use dalembert_constraints::{ConstraintSystem, ConstraintValues};
use dalembert_kinematics::MassMatrix;
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::sparse::linalg::lu::{factorize_symbolic_lu, LuRef, NumericLu, SymbolicLu};
use faer::sparse::{SparseColMatRef, SymbolicSparseColMatRef};
use faer::{Conj, MatMut, Par};

pub(crate) struct SparseKkt {
    dim: usize,
    col_ptr: Vec<usize>,
    row_idx: Vec<usize>,
    values: Vec<f64>,
    /// Position in `values` of each mass-block entry (9 per body, row-major).
    mass_map: Vec<usize>,
    /// Positions of `(n + r, c)` and `(c, n + r)` for each Jacobian pattern entry.
    jac_map: Vec<(usize, usize)>,
    symbolic: SymbolicLu<usize>,
    numeric: NumericLu<usize, f64>,
    factor_buf: MemBuffer,
    solve_buf: MemBuffer,
    /// Fixed ±1 probe for the singularity check, and its solution.
    probe: Vec<f64>,
    /// `‖K‖ ‖K⁻¹ probe‖ / ‖probe‖` above `1 / pivot_tolerance` means a singular matrix.
    pivot_tolerance: f64,
}

impl SparseKkt {
    pub fn new(sys: &ConstraintSystem, pivot_tolerance: f64) -> Result<Self, SingularKkt> {
        let n = sys.num_coordinates();
        let dim = n + sys.num_equations();
        let mut entries: Vec<(usize, usize)> = Vec::new();
        for b in 0..n / 3 {
            for r in 0..3 {
                for c in 0..3 {
                    entries.push((3 * b + r, 3 * b + c));
                }
            }
        }
        for &(r, c) in sys.pattern() {
            entries.push((n + r, c));
            entries.push((c, n + r));
        }
        // Compressed columns, rows sorted and unique.
        let mut cols: Vec<Vec<usize>> = vec![Vec::new(); dim];
        for &(r, c) in &entries {
            cols[c].push(r);
        }
        let (col_ptr, row_idx) = dalembert_constraints::sparse_pattern::compress_columns(cols);
        let pos = |r: usize, c: usize| dalembert_constraints::sparse_pattern::entry_position(&col_ptr, &row_idx, r, c);
        let mass_map = (0..n / 3)
            .flat_map(|b| (0..9).map(move |k| (3 * b + k / 3, 3 * b + k % 3)))
            .map(|(r, c)| pos(r, c))
            .collect();
        let jac_map = sys
            .pattern()
            .iter()
            .map(|&(r, c)| (pos(n + r, c), pos(c, n + r)))
            .collect();
        let symbolic = {
            let s = SymbolicSparseColMatRef::new_checked(dim, dim, &col_ptr, None, &row_idx);
            factorize_symbolic_lu(s, Default::default()).map_err(|e| SingularKkt(format!("symbolic LU: {e:?}")))?
        };
        let factor_buf = MemBuffer::new(symbolic.factorize_numeric_lu_scratch::<f64>(Par::Seq, Default::default()));
        let solve_buf = MemBuffer::new(symbolic.solve_in_place_scratch::<f64>(1, Par::Seq));
        let values = vec![0.0; row_idx.len()];
        Ok(SparseKkt {
            dim,
            col_ptr,
            row_idx,
            values,
            mass_map,
            jac_map,
            symbolic,
            numeric: NumericLu::new(),
            factor_buf,
            solve_buf,
            probe: vec![0.0; dim],
            pivot_tolerance,
        })
    }

    pub fn factor(
        &mut self,
        mass: &MassMatrix,
        _sys: &ConstraintSystem,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        self.values.iter_mut().for_each(|v| *v = 0.0);
        for (b, blk) in mass.blocks().iter().enumerate() {
            for k in 0..9 {
                self.values[self.mass_map[9 * b + k]] += blk[(k / 3, k % 3)];
            }
        }
        for (&(p, pt), &v) in self.jac_map.iter().zip(&vals.jacobian) {
            self.values[p] += v;
            self.values[pt] += v;
        }
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
            .map_err(|e| SingularKkt(format!("sparse LU: {e:?}")))?;
        // The sparse LU does not expose its pivots: estimate ‖K⁻¹‖ with one extra solve of a fixed
        // ±1 vector (a singular K amplifies it by ≈ 1/ε). Costs one pair of triangular solves.
        for (i, p) in self.probe.iter_mut().enumerate() {
            *p = if (i * 7 + 3) % 5 < 2 { -1.0 } else { 1.0 };
        }
        let mut probe = std::mem::take(&mut self.probe);
        self.solve(&mut probe);
        let growth = probe.iter().fold(0.0f64, |a, v| a.max(v.abs())) * super::kkt_scale(mass, vals);
        self.probe = probe;
        if !(growth.is_finite() && growth * self.pivot_tolerance < 1.0) {
            return Err(SingularKkt(format!("estimated condition number {growth:.3e}")));
        }
        Ok(())
    }

    pub fn solve(&mut self, x: &mut [f64]) {
        let rhs = MatMut::from_column_major_slice_mut(x, self.dim, 1);
        LuRef::new_unchecked(&self.symbolic, &self.numeric).solve_in_place_with_conj(
            Conj::No,
            rhs,
            Par::Seq,
            MemStack::new(&mut self.solve_buf),
        );
    }
}
