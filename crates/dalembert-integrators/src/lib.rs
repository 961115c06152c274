//! Time integration of the constrained equations of motion through the
//! [`Formulation`](dalembert_system::Formulation) interface (the integrators know the trait,
//! not the formulations).
//!
//! Methods ([`METHODS`], one file each under `methods/`):
//!
//! | method | order | evaluations per step | notes |
//! |---|---|---|---|
//! | semi-implicit (symplectic) Euler | 1 | 1 | `q̇ₙ₊₁ = q̇ₙ + h q̈ₙ`, `qₙ₊₁ = qₙ + h q̇ₙ₊₁`; bounded energy error |
//! | classic Runge–Kutta | 4 | 4 | slow energy drift |
//! | Dormand–Prince 5(4) | 5 | 6 (FSAL) | adaptive, PI step control, dense output of order 4 |
//! | generalized-α (index 3) | 2 | Newton iterations | implicit, unconditionally stable, `ρ∞` sets high-frequency damping; `C = 0` to the Newton tolerance |
//!
//! A method is a [`Stepper`] (one step from `(t, y)`) with a [`MethodEntry`] in the registry
//! ([`METHODS`]): its names, parameters, step control, which formulations it integrates and what
//! `dalembert trade` varies. Scenes, the command line, Python and `trade` read the registry; adding
//! a method is one file plus one line in [`METHODS`].
//!
//! [`Stabilization`] for the explicit methods: none (the violation drifts), Baumgarte
//! stabilization of the acceleration equation, or projection of `q` and `q̇` onto the manifold
//! after every accepted step (with the embedding formulation: coordinate partitioning). The
//! implicit method keeps the position constraints itself.
//!
//! [`integrate`] runs from `t₀` to `t_end`, hands every output sample to an observer as it is
//! produced (so output written before a failure is kept), and returns [`Statistics`]: steps,
//! evaluations, factorizations, Newton iterations, wall time, and the largest `|C|`, `|Ċ|` and
//! energy change seen. A failure is an [`IntegrationError`] with the time and the cause, carrying
//! the statistics up to it.

mod branch;
mod driver;
mod error;
mod methods;
mod options;
mod registry;
mod stabilization;
mod statistics;
mod stepper;
mod vector_state;

pub use branch::{BRANCH_SWITCH_ENERGY, BRANCH_SWITCH_JUMP, BRANCH_SWITCH_SHARE};
pub use driver::{
    integrate, integrate_cancellable, integrate_sensitivities, Integration, Perturbed, PerturbedSide, Sample,
};
pub use error::{IntegrationError, IntegrationFailure};
pub use methods::ali3p::ALI3P_AUTOMATIC_RATIO;
pub use options::IntegratorOptions;
pub use registry::{method_names, Applies, Build, Method, MethodEntry, Parameter, TradeAxis, MAX_PARAMETERS, METHODS};
pub use stabilization::Stabilization;
pub use statistics::Statistics;
pub use stepper::{Setup, StepControl, StepOutcome, Stepper, TangentField};
