//! Storage and factorization of the saddle-point ("KKT") matrix `[M C_qᵀ; C_q 0]`, and the same
//! matrix with the Jacobian restricted to chosen rows.

mod dense;
mod schur;
mod small_lu;
mod sparse;
mod sparse_schur;

pub(crate) use dense::DenseKkt;
pub(crate) use schur::{applicable as schur_applicable, SchurKkt};
pub(crate) use sparse::SparseKkt;
pub(crate) use sparse_schur::SparseSchurKkt;

use dalembert_constraints::{ConstraintSystem, ConstraintValues};
use dalembert_kinematics::MassMatrix;

/// A factorization failed or a pivot vanished: the matrix is (numerically) singular.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SingularKkt(pub String);

/// A factorization of the KKT matrix, refactored in place each evaluation.
pub(crate) enum KktSolver {
    Dense(Box<DenseKkt>),
    Schur(Box<SchurKkt>),
    Sparse(Box<SparseKkt>),
    SparseSchur(Box<SparseSchurKkt>),
}

impl KktSolver {
    /// Factors `[M C_qᵀ; C_q 0]` for the current values.
    pub fn factor(
        &mut self,
        mass: &MassMatrix,
        sys: &ConstraintSystem,
        vals: &ConstraintValues,
    ) -> Result<(), SingularKkt> {
        match self {
            KktSolver::Dense(d) => d.factor(mass, sys, vals),
            KktSolver::Schur(s) => s.factor(mass, sys, vals),
            KktSolver::Sparse(s) => s.factor(mass, sys, vals),
            KktSolver::SparseSchur(s) => s.factor(mass, sys, vals),
        }
    }

    /// Solves in place: `x` holds the right-hand side on entry, the solution on exit.
    pub fn solve(&mut self, sys: &ConstraintSystem, x: &mut [f64]) {
        match self {
            KktSolver::Dense(d) => d.solve(x),
            KktSolver::Schur(s) => s.solve(sys, x),
            KktSolver::Sparse(s) => s.solve(x),
            KktSolver::SparseSchur(s) => s.solve(sys, x),
        }
    }

    /// True when the last factorization is a Schur complement (not backward stable for the whole
    /// matrix: it squares the conditioning of `C_q M^-1/2`) whose condition estimate exceeds 1e3 (the estimates can fall short of the true condition number by a factor 10-100):
    /// its solution then gets one step of iterative refinement. Below that, its forward error is
    /// already ≈ 1e-10 relative.
    pub fn refines(&self) -> bool {
        const ILL_CONDITIONED: f64 = 1e3;
        match self {
            KktSolver::Schur(s) => s.condition > ILL_CONDITIONED,
            KktSolver::SparseSchur(s) => s.condition > ILL_CONDITIONED,
            _ => false,
        }
    }

    /// Back end name.
    pub fn name(&self) -> &'static str {
        match self {
            KktSolver::Dense(_) => "dense",
            KktSolver::Schur(_) => "schur",
            KktSolver::Sparse(_) => "sparse",
            KktSolver::SparseSchur(_) => "sparse-schur",
        }
    }
}

/// `y = K x` computed from the blocks, without the assembled matrix (for residual checks).
pub(crate) fn kkt_mul(mass: &MassMatrix, sys: &ConstraintSystem, vals: &ConstraintValues, x: &[f64], y: &mut [f64]) {
    let n = sys.num_coordinates();
    let (xt, xb) = x.split_at(n);
    let (yt, yb) = y.split_at_mut(n);
    yt.iter_mut().for_each(|v| *v = 0.0);
    mass.mul_add(1.0, xt, yt);
    sys.jacobian_transpose_mul_add(vals, 1.0, xb, yt);
    sys.jacobian_mul(vals, xt, yb);
}

/// Largest magnitude among the entries of `M` and `C_q` (scale of the residual check).
pub(crate) fn kkt_scale(mass: &MassMatrix, vals: &ConstraintValues) -> f64 {
    let m = mass
        .blocks()
        .iter()
        .flat_map(|b| b.iter())
        .fold(0.0f64, |a, v| a.max(v.abs()));
    vals.jacobian.iter().fold(m, |a, v| a.max(v.abs()))
}
