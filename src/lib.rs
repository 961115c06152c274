//! dalembert: constrained planar multibody dynamics.
//!
//! This facade re-exports the workspace crates. See `README.md` and `docs/`.

pub use dalembert_constraints as constraints;
pub use dalembert_kinematics as kinematics;
