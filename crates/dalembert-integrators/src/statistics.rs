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
    /// Steps of a conservative model at a fixed step whose change of `T + V` near a singular
    /// position (links lining up) was 100 times the earlier steps' and was undone by scaling the
    /// velocities: a stage that lands near the singular position amplifies the rounding in the
    /// state into a kick (`docs/stability.md`, "Kicks at singular positions").
    pub kicks_undone: u64,
    /// Events (a contact beginning or ending) a step was shortened to end at
    /// ([`dalembert_system::MultibodySystem::events`]).
    pub events: u64,
    /// Steps of a run with sensitivities whose tangents the method carried through its stages,
    /// solved with the run's own factorizations (fixed-step explicit methods,
    /// `docs/sensitivities.md`).
    pub tangents_carried: u64,
    /// Steps of a run with sensitivities whose tangents were found by taking the step again on
    /// each parameter's changed models (every other method, and a step the formulation could not
    /// solve a tangent on: redundant equations).
    pub tangents_differenced: u64,
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
    /// The run's energy scale: the largest of `|T + V|` at the start and the kinetic energy `T`
    /// after every accepted step. Changes of the energy are judged against it (the energy
    /// warning, the balance of a non-conservative model); at rest it is `|V|`.
    pub energy_scale: f64,
    /// Smallest accepted step.
    pub min_step_taken: f64,
    /// Largest accepted step.
    pub max_step_taken: f64,
}

impl Statistics {
    /// The statistics of a run made of this one and then `later` (a run started again from
    /// where this one stopped): counts and wall times added, the largest of the largest values,
    /// the smallest of the smallest steps (of the parts that took a step).
    pub fn then(&self, later: &Statistics) -> Statistics {
        let min_step_taken = match (self.steps, later.steps) {
            (0, _) => later.min_step_taken,
            (_, 0) => self.min_step_taken,
            _ => self.min_step_taken.min(later.min_step_taken),
        };
        Statistics {
            steps: self.steps + later.steps,
            rejected: self.rejected + later.rejected,
            evaluations: self.evaluations + later.evaluations,
            factorizations: self.factorizations + later.factorizations,
            newton_iterations: self.newton_iterations + later.newton_iterations,
            repartitions: self.repartitions + later.repartitions,
            handovers: self.handovers + later.handovers,
            kicks_undone: self.kicks_undone + later.kicks_undone,
            bridges: self.bridges + later.bridges,
            events: self.events + later.events,
            tangents_carried: self.tangents_carried + later.tangents_carried,
            tangents_differenced: self.tangents_differenced + later.tangents_differenced,
            wall_time: self.wall_time + later.wall_time,
            max_constraint_violation: self.max_constraint_violation.max(later.max_constraint_violation),
            max_velocity_violation: self.max_velocity_violation.max(later.max_velocity_violation),
            max_energy_change: self.max_energy_change.max(later.max_energy_change),
            max_projection_share: self.max_projection_share.max(later.max_projection_share),
            energy_scale: self.energy_scale.max(later.energy_scale),
            min_step_taken,
            max_step_taken: self.max_step_taken.max(later.max_step_taken),
        }
    }
}
