//! The interface every formulation implements and every integrator consumes.
//!
//! A formulation turns `(t, q, q̇)` into accelerations `q̈` and multipliers `λ` (so that reactions
//! follow from the multipliers); it reports the constraint residuals and the
//! energy, offers a Baumgarte-stabilized right-hand side (`docs/equations.md` §3), and projects a
//! state back onto the constraint manifold. Implementations create their workspaces once, at
//! construction: the methods allocate nothing.

use crate::{EquationRef, MultibodySystem};
use std::sync::Arc;
use thiserror::Error;

/// Baumgarte gains: the acceleration-level constraint equation `C_q q̈ = Q_d` becomes
/// `C_q q̈ = Q_d − 2α Ċ − β² C`, so that the violation obeys `C̈ + 2α Ċ + β² C = 0`
/// (`docs/equations.md` §3). A formulation takes `Option<Baumgarte>`: `None` leaves `Q_d` as is.
/// (The integrators' `Stabilization` chooses between no treatment, these gains and projection.)
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Baumgarte {
    /// Damping gain α (1/s).
    pub alpha: f64,
    /// Stiffness gain β (1/s).
    pub beta: f64,
}

impl Baumgarte {
    /// Gains in physical terms: the violation behaves as an oscillator of natural frequency
    /// `omega` (rad/s) and damping ratio `zeta`: `α = ζ ω`, `β = ω`.
    pub fn from_frequency(omega: f64, zeta: f64) -> Self {
        Baumgarte {
            alpha: zeta * omega,
            beta: omega,
        }
    }

    /// A default for step size `h`: critically damped at `ω = 1 / (10 h)`, slow enough for an
    /// explicit integrator to resolve (ωh = 0.1) and fast enough to remove drift within ≈ 30 steps.
    pub fn for_step(h: f64) -> Self {
        Self::from_frequency(0.1 / h, 1.0)
    }

    /// Writes `Q_d − 2α Ċ − β² C` (with `gains`) or `Q_d` (without) into `rhs`.
    pub fn apply(gains: Option<Baumgarte>, gamma: &[f64], c: &[f64], cdot: &[f64], rhs: &mut [f64]) {
        match gains {
            None => rhs.copy_from_slice(gamma),
            Some(Baumgarte { alpha, beta }) => {
                for i in 0..rhs.len() {
                    rhs[i] = gamma[i] - 2.0 * alpha * cdot[i] - beta * beta * c[i];
                }
            }
        }
    }
}

/// Kinetic and potential energy of a state.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Energy {
    /// `½ q̇ᵀ M q̇`.
    pub kinetic: f64,
    /// Gravity and springs.
    pub potential: f64,
}

impl Energy {
    /// `T + V`.
    pub fn total(&self) -> f64 {
        self.kinetic + self.potential
    }
}

/// What a formulation is built with: the settings a run gives every formulation (each takes what
/// applies to it).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct FormulationSettings {
    /// Redundant constraint equations: an error naming them, or minimum-norm multipliers.
    pub redundancy: RedundancyTreatment,
    /// Independent coordinates (velocity indices) a partitioning formulation keeps while they
    /// stay independent; `None`: its own choice.
    pub independent: Option<Vec<usize>>,
}

/// A formulation as the facade's registry lists it (`dalembert::FORMULATIONS`): its name in
/// scenes, flags and reports, what it is, and its constructor. A new formulation is a crate that
/// implements [`Formulation`] and defines its entry, plus one line in that registry.
pub struct FormulationEntry {
    /// Name in scenes, on the command line, in reports.
    pub name: &'static str,
    /// One line for help texts and the docs.
    pub summary: &'static str,
    /// True when it partitions the coordinates on dense matrices (`C_q`, `B_i` and the reduced
    /// mass matrix), which the run refuses to build beyond what memory holds.
    pub dense_partitioning: bool,
    /// True when its equations are the augmented index-3 system an implicit method integrates
    /// ([`Formulation::is_index3_augmented`]), known before it is built.
    pub index3_augmented: bool,
    /// Builds it on a system.
    pub build: BuildFormulation,
}

/// A formulation's constructor: builds it on a system with the run's settings.
pub type BuildFormulation =
    fn(Arc<dyn MultibodySystem>, &FormulationSettings) -> Result<Box<dyn Formulation>, DynamicsError>;

impl std::fmt::Debug for FormulationEntry {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name)
    }
}

/// How a formulation treats redundant constraint equations.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RedundancyTreatment {
    /// A rank-deficient `C_q` is an error naming the equations involved.
    #[default]
    Error,
    /// Solve on a maximal independent set of equations and report the minimum-norm `λ` (one
    /// admissible distribution of the reactions among redundant joints).
    MinimumNorm,
}

/// Failure of a dynamics evaluation or projection. Every variant carries the time.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum DynamicsError {
    /// The constraint Jacobian is rank deficient (redundant constraints or a singular position).
    #[error("t = {t}: constraint Jacobian is rank deficient (rank {rank} of {equations}); equations involved: {}", list(.involved), t = crate::Shortest(*.time))]
    RedundantConstraints {
        /// Time.
        time: f64,
        /// Numerical rank.
        rank: usize,
        /// Number of equations.
        equations: usize,
        /// The equations in the dependent set.
        involved: Vec<EquationRef>,
    },
    /// The mass matrix is singular on the motions the constraints allow (a massless body or a
    /// point mass whose rotation is free).
    #[error("t = {t}: mass matrix singular on the admissible motions; bodies without mass or inertia: {}", .bodies.join(", "), t = crate::Shortest(*.time))]
    SingularMass {
        /// Time.
        time: f64,
        /// Bodies with zero mass or inertia.
        bodies: Vec<String>,
    },
    /// A singular partition or factorization not explained by the two causes above.
    #[error("t = {t}: singular system: {what}", t = crate::Shortest(*.time))]
    Singular {
        /// Time.
        time: f64,
        /// Description.
        what: String,
    },
    /// A non-finite number in the state or the result.
    #[error("t = {t}: non-finite {what}", t = crate::Shortest(*.time))]
    NonFinite {
        /// Time.
        time: f64,
        /// What was not finite.
        what: String,
    },
    /// A force element left the range where its law is defined (e.g. a rotational spring wound
    /// past half a turn, whose deflection is measured within ±π).
    #[error("t = {t}: {element}: {what}", t = crate::Shortest(*.time))]
    ForceElement {
        /// Time.
        time: f64,
        /// The element (`force 'name'`).
        element: String,
        /// What happened.
        what: String,
    },
    /// A kinematic analysis (projection, position recovery) failed.
    #[error(transparent)]
    Kinematics(#[from] crate::ConstraintError),
    /// A slice handed to a formulation has the wrong length.
    #[error("{what} has length {got}, the model needs {expected}")]
    WrongLength {
        /// Which argument.
        what: &'static str,
        /// The length the model needs.
        expected: usize,
        /// The length given.
        got: usize,
    },
    /// A factorization reported an error.
    #[error("t = {t}: factorization failed: {what}", t = crate::Shortest(*.time))]
    Factorization {
        /// Time.
        time: f64,
        /// The solver's message.
        what: String,
    },
    /// A joint limit or a rigid contact could not be kept (`docs/limits.md`).
    #[error("t = {t}: the bound of {element}: {what}", t = crate::Shortest(*.time))]
    Limit {
        /// Time.
        time: f64,
        /// The element, as `joint 'NAME'` or `contact 'NAME'`.
        element: String,
        /// What happened.
        what: String,
    },
    /// Joint friction, or a rigid contact's, could not be solved (`docs/friction.md`).
    #[error("t = {t}: friction in {joint}: {what}", t = crate::Shortest(*.time))]
    Friction {
        /// Time.
        time: f64,
        /// The element (or elements), as `joint 'NAME'`, `joints 'A', 'B'` or `contact 'NAME'`.
        joint: String,
        /// What happened.
        what: String,
    },
}

impl DynamicsError {
    /// The time the failure happened, where the error carries it (every variant but
    /// `Kinematics` and `WrongLength`).
    pub fn time(&self) -> Option<f64> {
        match self {
            DynamicsError::RedundantConstraints { time, .. }
            | DynamicsError::SingularMass { time, .. }
            | DynamicsError::Singular { time, .. }
            | DynamicsError::NonFinite { time, .. }
            | DynamicsError::ForceElement { time, .. }
            | DynamicsError::Factorization { time, .. }
            | DynamicsError::Friction { time, .. }
            | DynamicsError::Limit { time, .. } => Some(*time),
            DynamicsError::Kinematics(_) | DynamicsError::WrongLength { .. } => None,
        }
    }
}

fn list(eqs: &[EquationRef]) -> String {
    crate::error::list(eqs)
}

/// Counters a formulation keeps (cumulative since construction).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct FormulationStats {
    /// Calls of [`Formulation::accelerations`].
    pub evaluations: u64,
    /// Numeric factorizations performed.
    pub factorizations: u64,
    /// Re-partitions of the coordinates (embedding formulations).
    pub repartitions: u64,
    /// Newton iterations spent in projections / position recovery.
    pub newton_iterations: u64,
    /// Projections coordinate partitioning handed over to the mass-orthogonal projection at
    /// singular positions (embedding and amalgamated formulations; [`crate::partition`]).
    pub handovers: u64,
}

/// The forward-dynamics interface shared by all formulations.
pub trait Formulation: Send {
    /// Short name, e.g. `"augmented"`.
    fn name(&self) -> &'static str;

    /// The system being solved.
    fn system(&self) -> &dyn MultibodySystem;

    /// Computes `q̈` and `λ` at `(t, q, q̇)`, with the Baumgarte terms added to the constraint
    /// right-hand side when `baumgarte` is given. `qdd` has length `n`, `lambda` length `m`.
    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        qd: &[f64],
        baumgarte: Option<Baumgarte>,
        qdd: &mut [f64],
        lambda: &mut [f64],
    ) -> Result<(), DynamicsError>;

    /// Writes `C(q, t)` and `Ċ = C_q q̇ + C_t` (each length `m`).
    fn residuals(&mut self, t: f64, q: &[f64], qd: &[f64], c: &mut [f64], cdot: &mut [f64]);

    /// Kinetic and potential energy.
    fn energy(&self, t: f64, q: &[f64], qd: &[f64]) -> Energy {
        let s = self.system();
        Energy {
            kinetic: s.kinetic_energy(q, qd),
            potential: s.potential_energy(t, q),
        }
    }

    /// Projects `q` onto `C(q, t) = 0` (Newton, to `tolerance`) and then `q̇` onto
    /// `C_q q̇ + C_t = 0`, each with the least mass-weighted change. Returns the Newton iterations.
    fn project(&mut self, t: f64, q: &mut [f64], qd: &mut [f64], tolerance: f64) -> Result<usize, DynamicsError>;

    /// Cumulative counters.
    fn stats(&self) -> FormulationStats;

    /// A step of the run begins at an accepted state, before its first evaluation. A formulation
    /// that chooses which coordinates are independent (coordinate partitioning) changes that
    /// choice only at a step's first evaluation or in [`Formulation::project`], never between the
    /// stages of one step (docs/stability.md). Default: nothing.
    fn begin_step(&mut self) {}

    /// True when this formulation's own equations are the augmented index-3 system
    /// `M v̇ + C_qᵀ λ = Q, C(q, t) = 0` that generalized-α integrates. Integrators that solve that
    /// system themselves refuse a formulation for which this is false, rather than silently
    /// replacing it (default: false).
    fn is_index3_augmented(&self) -> bool {
        false
    }

    /// Adds the generalized force `extra` (length `n`) to the applied forces of the following
    /// evaluations, or stops adding one (`None`). Joint friction ([`crate::Frictional`]) finds a
    /// formulation's response to a unit friction force with it. Returns false when the
    /// formulation cannot (default).
    fn set_extra_force(&mut self, _extra: Option<&[f64]>) -> bool {
        false
    }

    /// After [`Formulation::accelerations`] at a state: the change of `q̈` and `λ` per unit of an
    /// added generalized force `g` (length `n`), solved with the same factorization (a few
    /// triangular solves). Returns false where the formulation cannot (the caller then evaluates
    /// again with the force added, [`Formulation::set_extra_force`]). Default false.
    fn force_response(
        &mut self,
        _t: f64,
        _g: &[f64],
        _dqdd: &mut [f64],
        _dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        Ok(false)
    }

    /// After [`Formulation::accelerations`] at a state: the solution of the linearized equations
    /// `[M C_qᵀ; C_q 0] [Δq̈; Δλ] = [g; h]` (`g` length `n`, `h` length `m`) with the same
    /// factorization, as [`Formulation::force_response`] with a constraint right-hand side too.
    /// A run's sensitivities take the change of the accelerations along a tangent from it
    /// (`docs/sensitivities.md`). Returns false where the formulation cannot (redundant
    /// equations, a tree solved outright); the caller then differences whole evaluations.
    /// Default false.
    fn linear_response(
        &mut self,
        _t: f64,
        _g: &[f64],
        _h: &[f64],
        _dqdd: &mut [f64],
        _dlambda: &mut [f64],
    ) -> Result<bool, DynamicsError> {
        Ok(false)
    }

    /// A run starts (or starts again) at `(t, q, v)`: a formulation whose law has modes (joint
    /// friction: stick or slip) takes them from this state. Default: nothing.
    fn start_events(&mut self, _t: f64, _q: &[f64], _v: &[f64]) {}

    /// The event functions at `(t, q, v)` into `out` (length `num_events` of the system): the
    /// system's ([`MultibodySystem::events`]) by default; a formulation with modes writes its own
    /// for the elements that have them (a sign change ends a mode). Allocates nothing.
    fn events(&mut self, t: f64, q: &[f64], v: &[f64], out: &mut [f64]) {
        self.system().events(t, q, v, out);
    }

    /// True when a fixed-step method must shorten a step to end where event function `i` changes
    /// sign; false where the law does not change there (a stuck friction joint that its friction
    /// could not hold, already slipping by (F3), whose rate leaves the stick speed: (F3) is (F1),
    /// `docs/friction.md`), so that the switch is made at the step's end
    /// ([`Formulation::at_event`]) without taking the step again. Default: true.
    fn event_needs_location(&self, _i: usize) -> bool {
        true
    }

    /// How near zero event function `i` must be where a fixed-step method ends a step at its
    /// event (in the function's units). Default: 10⁻¹⁴.
    fn event_tolerance(&self, _i: usize) -> f64 {
        1e-14
    }

    /// At the end of a step shortened to end at an event, where `crossed[i]` says which event
    /// functions ([`MultibodySystem::events`]) changed sign over it: whatever the event asks of
    /// the state and the law (a joint whose slip stopped there made to stick, one whose stick
    /// ended made to slip, `docs/friction.md`). Returns true when it changed `v` or the law (a
    /// method must not reuse a derivative from before). Default: nothing.
    fn at_event(&mut self, _t: f64, _q: &[f64], _v: &mut [f64], _crossed: &[bool]) -> Result<bool, DynamicsError> {
        Ok(false)
    }

    /// The friction force of each friction element of the system ([`MultibodySystem::frictions`])
    /// at the last evaluation (N or N·m; empty without friction).
    fn friction_forces(&self) -> &[f64] {
        &[]
    }

    /// The force of each joint limit of the system ([`MultibodySystem::limits`]) at the last
    /// evaluation: its generalized force along the joint's coordinate (N or N·m; zero where the
    /// joint is free; empty without limits, `docs/limits.md`).
    fn limit_forces(&self) -> &[f64] {
        &[]
    }

    /// The kinetic energy the impulses at events took from the motion since the run began: the
    /// impacts at joint limits and rigid contacts, and the impulses that stop slips at their
    /// events (J; `docs/limits.md`, (L4)). Default 0.
    fn impact_loss(&self) -> f64 {
        0.0
    }
}
