//! A model, a formulation and an integrator, run together.

use crate::mechanism::Mechanism;
use dalembert_amalgamated::Amalgamated;
use dalembert_augmented::{Augmented, AugmentedOptions};
use dalembert_constraints::structure::dense_fits;
use dalembert_constraints::{ConstraintError, DynamicsError, Formulation, KinematicOptions, RedundancyTreatment};
use dalembert_embedding::{Embedding, EmbeddingOptions};
use dalembert_integrators::{integrate_cancellable, IntegrationFailure, IntegratorOptions, Sample, Statistics};
use std::sync::atomic::AtomicBool;
use thiserror::Error;

/// Which formulation of the equations of motion to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum FormulationKind {
    /// Lagrange multipliers, saddle-point system (`FORMULATIONS.md` §3).
    #[default]
    Augmented,
    /// Velocity transformation, one equation per degree of freedom (§4–§5); with projection it is
    /// coordinate partitioning.
    Embedding,
    /// One symmetric system in accelerations, constraint forces and independent accelerations (§6).
    Amalgamated,
}

impl FormulationKind {
    /// Every formulation, in the order of `FORMULATIONS.md`.
    pub const ALL: [FormulationKind; 3] = [
        FormulationKind::Augmented,
        FormulationKind::Embedding,
        FormulationKind::Amalgamated,
    ];

    /// Name used in reports and scene files.
    pub fn name(&self) -> &'static str {
        match self {
            FormulationKind::Augmented => "augmented",
            FormulationKind::Embedding => "embedding",
            FormulationKind::Amalgamated => "amalgamated",
        }
    }
}

/// Fraction of a run's energy scale (the larger of its largest kinetic energy and `|T + V|` at the
/// start) beyond which the change of `T + V` in a conservative model is reported as a numerical
/// blow-up rather than integration error (`dalembert simulate` warns; `--strict` fails).
pub const ENERGY_WARNING_FRACTION: f64 = 1e-2;

/// The warning for a run of a conservative model whose energy changed by `change` (J) while its
/// energy scale was `scale` (J), or `None` when the change is within
/// [`ENERGY_WARNING_FRACTION`] of the scale.
pub fn energy_warning(change: f64, scale: f64) -> Option<String> {
    let limit = ENERGY_WARNING_FRACTION * scale;
    // A NaN change is reported too.
    let within = change
        .partial_cmp(&limit)
        .is_some_and(|o| o != std::cmp::Ordering::Greater);
    (!within).then(|| {
        format!(
            "the energy of this conservative model changed by {change:.3e} J, more than {:.0} % of its energy scale {scale:.3e} J: the run is not trustworthy (try a smaller step, projection, or another integrator)",
            100.0 * ENERGY_WARNING_FRACTION
        )
    })
}

/// Why a simulation could not start or did not finish.
#[derive(Debug, Error)]
pub enum SimulationError {
    /// The initial configuration could not be assembled or made consistent.
    #[error("initial state: {0}")]
    Assembly(#[from] ConstraintError),
    /// The formulation could not be set up.
    #[error("setup: {0}")]
    Setup(#[from] DynamicsError),
    /// The run stopped early (the statistics up to then are inside).
    #[error("{0}")]
    Integration(#[from] IntegrationFailure),
}

/// A model with an initial state and the settings of a run.
#[derive(Debug, Clone)]
pub struct Simulation {
    /// The model (planar or spatial).
    pub model: Mechanism,
    /// Initial positions (approximate is fine: [`Simulation::assemble`] fixes them).
    pub q: Vec<f64>,
    /// Initial velocities (made consistent by [`Simulation::assemble`]).
    pub qd: Vec<f64>,
    /// Start time.
    pub start: f64,
    /// End time.
    pub end: f64,
    /// Formulation.
    pub formulation: FormulationKind,
    /// Redundant constraint equations: an error naming them (default), or solved on an
    /// independent set with minimum-norm multipliers (`docs/sign-conventions.md`).
    pub redundancy: RedundancyTreatment,
    /// Integrator settings.
    pub integrator: IntegratorOptions,
    /// Weights of the initial velocities in [`Simulation::assemble`]: a coordinate whose velocity
    /// was given explicitly gets a large weight so that it changes least; `f64::INFINITY` holds it
    /// exactly when the constraints allow (otherwise it gets weight 1e6 against the others). `None`:
    /// all equal.
    pub velocity_weights: Option<Vec<f64>>,
    /// Independent coordinates (velocity indices) of the embedding formulation's partition, used
    /// while they stay independent; `None`: chosen by the formulation. Other formulations ignore
    /// it.
    pub independent: Option<Vec<usize>>,
}

impl Simulation {
    /// Assembles the initial state: position analysis from the given `q` (least change), then the
    /// least (weighted) change to `q̇` that satisfies the velocity constraints.
    pub fn assemble(&mut self) -> Result<(), SimulationError> {
        let opts = KinematicOptions::default();
        let sys = self.model.as_system().constraints();
        sys.solve_positions(self.start, &mut self.q, &opts)?;
        sys.solve_velocities_weighted(
            self.start,
            &self.q,
            &mut self.qd,
            self.velocity_weights.as_deref(),
            &opts,
        )?;
        Ok(())
    }

    /// Builds the chosen formulation.
    pub fn formulation(&self) -> Result<Box<dyn Formulation>, SimulationError> {
        // The embedding and amalgamated formulations still partition the coordinates on a dense
        // C_q (m × n) and both store B_i by rows (n × dof) and the reduced mass matrix (dof ×
        // dof): refuse models whose dense matrices would not fit, naming the size, instead of
        // failing in the allocator.
        let (n, m) = (self.model.num_velocities(), self.model.num_equations());
        let too_large = match self.formulation {
            FormulationKind::Augmented => None,
            _ if !dense_fits(m, n) => Some((m, n)),
            _ if !dense_fits(n, n.saturating_sub(m)) => Some((n, n - m)),
            _ => None,
        };
        if let Some((rows, cols)) = too_large {
            return Err(SimulationError::Setup(DynamicsError::Kinematics(
                ConstraintError::TooLarge {
                    what: format!(
                        "the {} formulation (dense coordinate partitioning)",
                        self.formulation.name()
                    ),
                    hint: "use the augmented formulation, which is sparse",
                    rows,
                    cols,
                },
            )));
        }
        let redundancy = self.redundancy;
        let system = self.model.system();
        Ok(match self.formulation {
            FormulationKind::Augmented => Box::new(Augmented::new(
                system,
                AugmentedOptions {
                    redundancy,
                    ..Default::default()
                },
            )?),
            FormulationKind::Embedding => Box::new(Embedding::new(
                system,
                EmbeddingOptions {
                    redundancy,
                    independent: self.independent.clone(),
                    ..Default::default()
                },
            )),
            FormulationKind::Amalgamated => Box::new(Amalgamated::new(system, redundancy)),
        })
    }

    /// Runs from the current initial state, handing every output sample to `observer`.
    pub fn run(&self, observer: &mut dyn FnMut(&Sample<'_>)) -> Result<Statistics, SimulationError> {
        self.run_cancellable(observer, &AtomicBool::new(false))
    }

    /// [`Simulation::run`] that stops after the step during which `cancel` was set (e.g. by a
    /// Ctrl-C handler), with `IntegrationError::Interrupted` carrying the time.
    pub fn run_cancellable(
        &self,
        observer: &mut dyn FnMut(&Sample<'_>),
        cancel: &AtomicBool,
    ) -> Result<Statistics, SimulationError> {
        let mut f = self.formulation()?;
        Ok(integrate_cancellable(
            f.as_mut(),
            self.start,
            self.end,
            &self.q,
            &self.qd,
            &self.integrator,
            observer,
            cancel,
        )?)
    }
}
