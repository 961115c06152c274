//! Storage and factorization of the saddle-point ("KKT") matrix `[M C_qᵀ; C_q 0]` (`FORMULATIONS.md`
//! §3), chosen once per system by [`Backend`] and refactored in place each evaluation.

mod dense;
mod schur;
mod sparse;
mod sparse_schur;

use dense::DenseKkt;
use schur::SchurKkt;
use sparse::SparseKkt;
use sparse_schur::SparseSchurKkt;

use super::LinalgError;
use crate::{BlockDiagonal, ConstraintPattern, ConstraintSet, ConstraintValues};

/// The back ends' failure: a message (turned into [`LinalgError::Singular`]).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct SingularKkt(pub String);

impl From<SingularKkt> for LinalgError {
    fn from(e: SingularKkt) -> Self {
        LinalgError::Singular(e.0)
    }
}

/// Which linear-algebra back end solves the saddle-point system.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Backend {
    /// Up to the dense limit (`n + m` unknowns): the Schur complement when the mass blocks allow it
    /// (positive definite or diagonal), dense LU otherwise; above it the sparse Schur complement
    /// when every mass block is positive definite; with singular mass blocks the dense back ends
    /// up to twice the limit and the sparse LU above.
    #[default]
    Auto,
    /// Dense LU with partial pivoting of the whole saddle-point matrix.
    Dense,
    /// Range space: Cholesky of `S = C_q M⁻¹ C_qᵀ`, with a small reduced system for coordinates
    /// without inertia (needs mass blocks that are positive definite, or diagonal).
    Schur,
    /// Sparse LU of the saddle-point matrix with a symbolic analysis reused across evaluations.
    Sparse,
    /// Sparse Cholesky of `S = C_q M⁻¹ C_qᵀ` (positive definite mass blocks), symbolic analysis
    /// reused: linear cost for chains.
    SparseSchur,
}

/// The saddle-point matrix of one system, factored by the back end chosen at construction.
pub struct SaddlePoint {
    kind: Kind,
}

impl std::fmt::Debug for SaddlePoint {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SaddlePoint").field("backend", &self.name()).finish()
    }
}

enum Kind {
    Dense(Box<DenseKkt>),
    Schur(Box<SchurKkt>),
    Sparse(Box<SparseKkt>),
    SparseSchur(Box<SparseSchurKkt>),
}

/// `Auto` resolved for a system: the back end [`SaddlePoint::new`] would build.
pub fn resolve(backend: Backend, mass: &BlockDiagonal, m: usize, dense_limit: usize) -> Backend {
    let n = mass.dim();
    let spd = mass.clone().invert_blocks(&mut mass.clone()).is_ok();
    match backend {
        Backend::Auto if n + m > dense_limit && spd => Backend::SparseSchur,
        Backend::Auto if n + m > 2 * dense_limit => Backend::Sparse,
        Backend::Auto if schur::applicable(mass, m) => Backend::Schur,
        Backend::Auto => Backend::Dense,
        other => other,
    }
}

impl SaddlePoint {
    /// Chooses the back end for a system with mass matrix `mass` (its block structure and which
    /// blocks are positive definite, at [`crate::MultibodySystem::reference_positions`];
    /// `mass_is_constant` lets the inverse blocks be computed once)
    /// and constraints `sys`, and sets it up (symbolic analysis, storage, scratch).
    pub fn new(
        backend: Backend,
        mass: &BlockDiagonal,
        mass_is_constant: bool,
        sys: &(impl ConstraintSet + ?Sized),
        dense_limit: usize,
        pivot_tolerance: f64,
    ) -> Result<Self, LinalgError> {
        let m = sys.num_equations();
        let pattern = sys.pattern();
        let kind = match resolve(backend, mass, m, dense_limit) {
            Backend::Schur if !schur::applicable(mass, m) => {
                return Err(LinalgError::Singular(
                    "the Schur back end needs mass blocks that are positive definite or diagonal".into(),
                ))
            }
            Backend::Schur => Kind::Schur(Box::new(SchurKkt::new(
                mass,
                mass_is_constant,
                pattern,
                pivot_tolerance,
            ))),
            Backend::SparseSchur => {
                if mass.clone().invert_blocks(&mut mass.clone()).is_err() {
                    return Err(LinalgError::Singular(
                        "the sparse Schur back end needs every body's mass and inertia positive".into(),
                    ));
                }
                Kind::SparseSchur(Box::new(SparseSchurKkt::new(
                    mass,
                    mass_is_constant,
                    sys,
                    pivot_tolerance,
                )?))
            }
            Backend::Sparse => Kind::Sparse(Box::new(SparseKkt::new(mass, pattern, pivot_tolerance)?)),
            _ => Kind::Dense(Box::new(DenseKkt::new(mass.dim(), m, pivot_tolerance))),
        };
        Ok(SaddlePoint { kind })
    }

    /// Factors `[M C_qᵀ; C_q 0]` for the current values.
    pub fn factor(
        &mut self,
        mass: &BlockDiagonal,
        pattern: &ConstraintPattern,
        vals: &ConstraintValues,
    ) -> Result<(), LinalgError> {
        Ok(match &mut self.kind {
            Kind::Dense(d) => d.factor(mass, pattern, vals),
            Kind::Schur(s) => s.factor(mass, pattern, vals),
            Kind::Sparse(s) => s.factor(mass, pattern, vals),
            Kind::SparseSchur(s) => s.factor(mass, pattern, vals),
        }?)
    }

    /// Solves in place: `x` holds the right-hand side `[top (n); bottom (m)]` on entry, the solution
    /// on exit.
    pub fn solve(&mut self, pattern: &ConstraintPattern, x: &mut [f64]) {
        match &mut self.kind {
            Kind::Dense(d) => d.solve(x),
            Kind::Schur(s) => s.solve(pattern, x),
            Kind::Sparse(s) => s.solve(x),
            Kind::SparseSchur(s) => s.solve(pattern, x),
        }
    }

    /// True when the last factorization is a Schur complement (not backward stable for the whole
    /// matrix: it squares the conditioning of `C_q M^-1/2`) whose condition estimate exceeds 1e3 (the
    /// estimates can fall short of the true condition number by a factor 10-100): its solution then
    /// deserves one step of iterative refinement. Below that, its forward error is already ≈ 1e-10
    /// relative.
    pub fn refines(&self) -> bool {
        const ILL_CONDITIONED: f64 = 1e3;
        match &self.kind {
            Kind::Schur(s) => s.condition > ILL_CONDITIONED,
            Kind::SparseSchur(s) => s.condition > ILL_CONDITIONED,
            _ => false,
        }
    }

    /// Back end name: `"dense"`, `"schur"`, `"sparse"` or `"sparse-schur"`.
    pub fn name(&self) -> &'static str {
        match &self.kind {
            Kind::Dense(_) => "dense",
            Kind::Schur(_) => "schur",
            Kind::Sparse(_) => "sparse",
            Kind::SparseSchur(_) => "sparse-schur",
        }
    }
}

/// `y = K x` computed from the blocks, without the assembled matrix (for residual checks).
pub fn kkt_mul(
    mass: &BlockDiagonal,
    sys: &(impl ConstraintSet + ?Sized),
    vals: &ConstraintValues,
    x: &[f64],
    y: &mut [f64],
) {
    let n = sys.num_coordinates();
    let (xt, xb) = x.split_at(n);
    let (yt, yb) = y.split_at_mut(n);
    yt.iter_mut().for_each(|v| *v = 0.0);
    mass.mul_add(1.0, xt, yt);
    sys.jacobian_transpose_mul_add(vals, 1.0, xb, yt);
    sys.jacobian_mul(vals, xt, yb);
}

/// Largest magnitude among the entries of `M` and `C_q` (scale of the residual check).
pub fn kkt_scale(mass: &BlockDiagonal, vals: &ConstraintValues) -> f64 {
    vals.jacobian.iter().fold(mass.max_abs(), |a, v| a.max(v.abs()))
}
