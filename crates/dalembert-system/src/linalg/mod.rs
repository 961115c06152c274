//! The one linear-algebra layer of dalembert: every formulation and the implicit integrator
//! factor through it, with the symbolic analysis done once per pattern and the numeric
//! factorization into storage allocated at setup.
//!
//! * [`small_lu`]: unblocked dense LU for matrices up to a few dozen rows;
//! * [`small_ldlt`]: square-root-free Cholesky `L D Lᵀ` of a small definite block (either sign);
//! * [`dense`]: dense LU and Cholesky (faer's in-place kernels) in storage allocated once;
//! * [`sparse_lu`]: faer's sparse LU behind a fixed pattern (scatter positions computed once);
//! * [`pattern_lu`]: a matrix given by an entry list, dense LU when small and sparse LU above (the
//!   implicit integrator's iteration matrix);
//! * [`saddle_point`]: the saddle-point matrix `[M C_qᵀ; C_q 0]` by dense LU, dense Schur
//!   complement (Cholesky of `C_q M⁻¹ C_qᵀ`), sparse LU, sparse Schur complement
//!   ([`crate::gram`]'s sparse Cholesky), or the block `L D Lᵀ` along the body–joint tree (linear
//!   cost, loops closed by a small dense Schur complement);
//! * [`LinalgError`]: typed failures, keeping the solver's own error as the source.
//!
//! faer is the factorization library (dense and sparse LU, sparse Cholesky with a reusable symbolic
//! analysis and caller-provided scratch: no allocation in a numeric refactorization);
//! `shared/LINALG-NOTES.md` records what was verified about it.

pub mod dense;
pub mod full_pivot;
pub mod pattern_lu;
mod rows;
pub mod saddle_point;
pub mod small_ldlt;
pub mod small_lu;
pub mod sparse_lu;

pub use dense::{DenseCholesky, DenseLu};
pub use full_pivot::FullPivot;
pub use pattern_lu::PatternLu;
pub use saddle_point::{Backend, SaddlePoint};
pub use small_lu::SmallLu;
pub use sparse_lu::SparseLu;

use thiserror::Error;

/// A factorization failed or found its matrix (numerically) singular.
#[derive(Debug, Clone, Error)]
#[non_exhaustive]
pub enum LinalgError {
    /// A pivot or a condition estimate says the matrix is singular to working precision.
    #[error("{0}")]
    Singular(String),
    /// The sparse LU failed (symbolic analysis or numeric factorization).
    #[error("{what}")]
    SparseLu {
        /// What was being factored.
        what: &'static str,
        /// faer's error.
        #[source]
        source: faer::sparse::linalg::LuError,
    },
    /// The sparse symbolic analysis could not be built.
    #[error("{what}")]
    Symbolic {
        /// What was being analysed.
        what: &'static str,
        /// faer's error.
        #[source]
        source: faer::sparse::FaerError,
    },
}
