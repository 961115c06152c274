//! What a run spent and how far it drifted.

use std::time::Duration;

/// Counters and monitors of one integration run.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Statistics {
    /// Accepted steps.
    pub steps: u64,
    /// Rejected steps (adaptive methods).
    pub rejected: u64,
    /// Right-hand-side evaluations (`q̈, λ` solves).
    pub evaluations: u64,
    /// Numeric factorizations performed by the formulation.
    pub factorizations: u64,
    /// Newton iterations (projection).
    pub newton_iterations: u64,
    /// Coordinate re-partitions.
    pub repartitions: u64,
    /// Projections handed over from coordinate partitioning to the mass-orthogonal projection at
    /// singular positions (embedding and amalgamated formulations).
    pub handovers: u64,
    /// Singular positions an adaptive method's steps collapsed at and the loop bridged with checked
    /// steps (one step against two half steps; integrators/src/driver/bridge.rs). A bridged run is
    /// accurate to about 31 × its tolerances there, not to its tolerances.
    pub bridges: u64,
    /// Wall time of the integration loop (excluding the observer's own time is not attempted).
    pub wall_time: Duration,
    /// Largest `‖C‖∞` after any accepted step.
    pub max_constraint_violation: f64,
    /// Largest `‖Ċ‖∞` after any accepted step.
    pub max_velocity_violation: f64,
    /// Largest `|E − E₀|` after any accepted step.
    pub max_energy_change: f64,
    /// Largest share of the kinetic energy one step's velocity projection removed:
    /// `T(q, v − v_p) / T_max`, with `v` the stepped and `v_p` the projected velocity and `T_max` the
    /// largest kinetic energy of the run so far (0 without projection). An accurate step leaves a
    /// drift of the order of its local error; a large share means the projection moved the motion
    /// to another branch at a singular position (the run stops above
    /// [`BRANCH_SWITCH_SHARE`](crate::BRANCH_SWITCH_SHARE)).
    pub max_projection_share: f64,
    /// Smallest accepted step.
    pub min_step_taken: f64,
    /// Largest accepted step.
    pub max_step_taken: f64,
}
