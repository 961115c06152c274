//! dalembert: constrained multibody dynamics, planar and spatial.
//!
//! This facade re-exports the workspace crates and adds what ties them together: [`Simulation`]
//! (a model, a formulation and an integrator, run to an end time) and [`CsvOutput`] (streamed
//! results with reactions and driver efforts).
//!
//! | crate | holds |
//! |---|---|
//! | [`system`] | the seam: how formulations and integrators see any multibody system; the linear-algebra layer |
//! | [`kinematics`] | planar bodies, coordinates, point kinematics, mass matrix, applied forces, time functions |
//! | [`constraints`] | planar joints, drivers, `C`, `C_q`, `C_t`, `Q_d`, reactions (structure and kinematic analysis are the seam's: [`system`]) |
//! | [`spatial`] | spatial bodies (Euler parameters, body-frame angular velocity), the spatial joint set, forces |
//! | [`augmented`] | the augmented (Lagrange multiplier) formulation, reactions, inverse dynamics |
//! | [`embedding`] | the embedding (velocity transformation) formulation, coordinate partitioning |
//! | [`amalgamated`] | the amalgamated formulation |
//! | [`integrators`] | symplectic Euler, RK4, Dormand–Prince, generalized-α; Baumgarte and projection |
//!
//! The mathematics is in `docs/` and in each crate's documentation.

pub mod analysis;
pub mod animation;
pub mod builder;
pub mod code_force;
pub mod energy;
pub mod equilibrium;
mod joint_map;
pub mod linearization;
pub mod mechanism;
pub mod modes;
pub mod output;
pub mod relaxation;
pub mod scene;
pub mod sensitivity;
pub mod simulation;
pub mod simulator;
pub mod sweep;
pub mod trade;

pub use dalembert_amalgamated as amalgamated;
pub use dalembert_augmented as augmented;
pub use dalembert_constraints as constraints;
pub use dalembert_embedding as embedding;
pub use dalembert_integrators as integrators;
pub use dalembert_kinematics as kinematics;
pub use dalembert_spatial as spatial;
pub use dalembert_system as system;

pub use analysis::{CheckReport, Recording};
pub use builder::ModelBuilder;
pub use equilibrium::{Equilibrium, EquilibriumError};
pub use linearization::{About, Linearization, LinearizationError, LinearizeOptions};
pub use mechanism::Mechanism;
pub use modes::Modes;
pub use output::CsvOutput;
pub use scene::{Scene, SceneError, SceneValue};
pub use sensitivity::{SensitivityError, SensitivityRecording, SensitivityRequest};
pub use simulation::{
    energy_warning, Coordinates, FormulationKind, Simulation, SimulationError, ENERGY_WARNING_FRACTION, FORMULATIONS,
};
pub use simulator::{Moved, Simulator, SimulatorError};
