//! Time integration of the constrained equations of motion through the
//! [`Formulation`](dalembert_system::Formulation) interface (the integrators know the trait,
//! not the formulations).
//!
//! Methods ([`Method`]):
//!
//! | method | order | evaluations per step | notes |
//! |---|---|---|---|
//! | semi-implicit (symplectic) Euler | 1 | 1 | `q̇ₙ₊₁ = q̇ₙ + h q̈ₙ`, `qₙ₊₁ = qₙ + h q̇ₙ₊₁`; bounded energy error |
//! | classic Runge–Kutta | 4 | 4 | slow energy drift |
//! | Dormand–Prince 5(4) | 5 | 6 (FSAL) | adaptive, PI step control, dense output of order 4 |
//! | generalized-α (index 3) | 2 | Newton iterations | implicit, unconditionally stable, `ρ∞` sets high-frequency damping; `C = 0` to the Newton tolerance |
//!
//! Constraint treatment ([`ConstraintTreatment`]) for the explicit methods: none (the violation
//! drifts), Baumgarte stabilization of the acceleration equation, or projection of `q` and `q̇`
//! onto the manifold after every accepted step (with the embedding formulation: coordinate
//! partitioning). The implicit method keeps the position constraints itself.
//!
//! [`integrate`] runs from `t₀` to `t_end`, hands every output sample to an observer as it is
//! produced (so output written before a failure is kept), and returns [`Statistics`]: steps,
//! evaluations, factorizations, Newton iterations, wall time, and the largest `|C|`, `|Ċ|` and
//! energy change seen. A failure is an [`IntegrationError`] with the time and the cause, carrying
//! the statistics up to it.

mod dopri5;
mod driver;
mod error;
mod explicit;
mod generalized_alpha;
mod options;
mod statistics;
mod vector_state;

pub use driver::{integrate, integrate_cancellable, Sample};
pub use error::{IntegrationError, IntegrationFailure};
pub use options::{ConstraintTreatment, IntegratorOptions, Method};
pub use statistics::Statistics;
