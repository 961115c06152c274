//! A model, a formulation and an integrator, run together.

use crate::joint_map::{JointMap, JointStart};
use crate::mechanism::Mechanism;
use dalembert_integrators::{
    integrate_cancellable, IntegrationError, IntegrationFailure, IntegratorOptions, Sample, Statistics,
};
use dalembert_system::structure::dense_fits;
use dalembert_system::{ConstraintError, DynamicsError, Formulation, KinematicOptions, RedundancyTreatment};
use dalembert_system::{FormulationEntry, FormulationSettings, ModelError, MultibodySystem};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use thiserror::Error;

/// The registry of formulations: every place that offers a choice of formulation (scenes, the
/// command line, Python, `dalembert trade`, the tests that run every formulation) reads it. A new
/// formulation is a crate that implements [`Formulation`] and defines its
/// [`FormulationEntry`], plus one line here.
pub const FORMULATIONS: [&FormulationEntry; 3] = [
    &dalembert_augmented::ENTRY,
    &dalembert_embedding::ENTRY,
    &dalembert_amalgamated::ENTRY,
];

/// Which formulation of the equations of motion to use: an entry of [`FORMULATIONS`].
#[derive(Clone, Copy)]
pub struct FormulationKind(&'static FormulationEntry);

#[allow(non_upper_case_globals)]
impl FormulationKind {
    /// Lagrange multipliers, saddle-point system (`docs/equations.md` §3).
    pub const Augmented: FormulationKind = FormulationKind(&dalembert_augmented::ENTRY);
    /// Velocity transformation, one equation per degree of freedom (§4–§5); with projection it is
    /// coordinate partitioning.
    pub const Embedding: FormulationKind = FormulationKind(&dalembert_embedding::ENTRY);
    /// One symmetric system in accelerations, constraint forces and independent accelerations (§6).
    pub const Amalgamated: FormulationKind = FormulationKind(&dalembert_amalgamated::ENTRY);
}

impl PartialEq for FormulationKind {
    fn eq(&self, other: &Self) -> bool {
        self.0.name == other.0.name
    }
}

impl Eq for FormulationKind {}

impl std::fmt::Debug for FormulationKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.0.name)
    }
}

impl Default for FormulationKind {
    /// The first of [`FORMULATIONS`] (augmented).
    fn default() -> Self {
        FormulationKind(FORMULATIONS[0])
    }
}

impl FormulationKind {
    /// Every formulation, in the order of [`FORMULATIONS`].
    pub const ALL: [FormulationKind; FORMULATIONS.len()] = {
        let mut all = [FormulationKind(FORMULATIONS[0]); FORMULATIONS.len()];
        let mut k = 0;
        while k < all.len() {
            all[k] = FormulationKind(FORMULATIONS[k]);
            k += 1;
        }
        all
    };

    /// Name used in reports and scene files (the entry's).
    pub const fn name(&self) -> &'static str {
        self.0.name
    }

    /// The registry entry.
    pub fn entry(&self) -> &'static FormulationEntry {
        self.0
    }

    /// The names a scene or the command line may use, in the order of [`FORMULATIONS`].
    pub const NAMES: &'static [&'static str] = &{
        let mut names = [""; FORMULATIONS.len()];
        let mut k = 0;
        while k < names.len() {
            names[k] = FORMULATIONS[k].name;
            k += 1;
        }
        names
    };

    /// Parses a scene or command-line name.
    pub fn parse(s: &str) -> Option<Self> {
        FormulationKind::ALL.into_iter().find(|k| k.name() == s)
    }
}

/// The coordinates a run integrates.
///
/// ```
/// // Two links on revolute joints about y, in joint coordinates: the samples are the model's
/// // absolute coordinates (per body x, y, z, four Euler parameters) and multipliers.
/// let text = r#"
/// [scene]
/// gravity = [0.0, 0.0, -9.81]
/// [[bodies]]
/// name = "upper"
/// mass = 1.0
/// shape = { box = [1.0, 0.1, 0.1] }
/// position = [0.5, 0.0, 0.0]
/// [[bodies]]
/// name = "lower"
/// mass = 1.0
/// shape = { box = [1.0, 0.1, 0.1] }
/// position = [1.5, 0.0, 0.0]
/// [[joints]]
/// name = "shoulder"
/// type = "revolute"
/// bodies = ["ground", "upper"]
/// at = [0.0, 0.0, 0.0]
/// axis = [0.0, 1.0, 0.0]
/// [[joints]]
/// name = "elbow"
/// type = "revolute"
/// bodies = ["upper", "lower"]
/// at = [1.0, 0.0, 0.0]
/// axis = [0.0, 1.0, 0.0]
/// [simulation]
/// end = 0.5
/// coordinates = "joint"
/// "#;
/// let scene = dalembert::Scene::from_toml(text, "double pendulum")?;
/// assert_eq!(scene.settings.coordinates, dalembert::Coordinates::Joint);
/// let (mut z, mut lambda) = (0.0, 0.0);
/// scene.simulation().run(&mut |s| {
///     z = s.q[9]; // the lower link's centre of mass, height
///     lambda = s.lambda[2]; // the shoulder's vertical reaction component
/// })?;
/// assert!(z < -0.5, "the pendulum falls: z = {z}");
/// assert!(lambda.abs() > 0.0, "the reactions are the model's multipliers");
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
#[non_exhaustive]
pub enum Coordinates {
    /// The model's own: absolute coordinates of every body, joints as constraint equations.
    #[default]
    Absolute,
    /// One coordinate per joint, for a spatial tree of revolute and prismatic joints
    /// (`docs/joint-coordinates.md`): integrated without constraint equations, solved by the
    /// articulated-body algorithm; every output sample is mapped back to the absolute coordinates
    /// and its accelerations, multipliers and reactions are the model's own formulation's there.
    Joint,
}

impl Coordinates {
    /// Names in scene files, flags and keywords.
    pub const NAMES: &'static [&'static str] = &["absolute", "joint"];

    /// Name used in reports and scene files.
    pub fn name(&self) -> &'static str {
        match self {
            Coordinates::Absolute => "absolute",
            Coordinates::Joint => "joint",
        }
    }

    /// The coordinates called `name`.
    pub fn parse(name: &str) -> Option<Self> {
        match name {
            "absolute" => Some(Coordinates::Absolute),
            "joint" => Some(Coordinates::Joint),
            _ => None,
        }
    }
}

/// Fraction of a run's energy scale (the larger of its largest kinetic energy and `|T + V|` at the
/// start) beyond which the change of `T + V` in a conservative model, or of the energy balance
/// `E − W` in another, is reported as a numerical blow-up rather than integration error
/// (`dalembert simulate` warns; `--strict` fails).
pub const ENERGY_WARNING_FRACTION: f64 = 1e-2;

/// The warning for a run whose energy changed by `change` (J) while its energy scale was `scale`
/// (J), or `None` when the change is within [`ENERGY_WARNING_FRACTION`] of the scale. For a
/// conservative model `change` is that of `T + V`; for another (`balance`), that of the energy
/// balance `E − W` ([`crate::energy::EnergyBalance`]).
pub fn energy_warning(change: f64, scale: f64, balance: bool) -> Option<String> {
    let limit = ENERGY_WARNING_FRACTION * scale;
    // A NaN change is reported too.
    let within = change
        .partial_cmp(&limit)
        .is_some_and(|o| o != std::cmp::Ordering::Greater);
    let what = match balance {
        false => "the energy of this conservative model",
        true => "the energy balance E − W of this model (energy less the work of its forces and drivers)",
    };
    (!within).then(|| {
        format!(
            "{what} changed by {change:.3e} J, more than {:.0} % of its energy scale {scale:.3e} J: the run is not trustworthy (try a smaller step, projection, or another integrator)",
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
    /// The model cannot run in joint coordinates (the error names the element).
    #[error("joint coordinates: {0}")]
    JointCoordinates(#[source] ModelError),
}

impl SimulationError {
    /// The time the run stopped at, where the error carries it (a failure during the run; `None`
    /// for a failure before it).
    pub fn time(&self) -> Option<f64> {
        match self {
            SimulationError::Integration(f) => f.error.time(),
            SimulationError::Setup(d) => d.time(),
            _ => None,
        }
    }

    /// The time a cancelled run reached (`IntegrationError::Interrupted`), or `None` for any
    /// other failure.
    pub fn interrupted_at(&self) -> Option<f64> {
        match self {
            SimulationError::Integration(f) => match f.error {
                IntegrationError::Interrupted { time } => Some(time),
                _ => None,
            },
            _ => None,
        }
    }
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
    /// The coordinates integrated (default: the model's absolute ones).
    pub coordinates: Coordinates,
    /// The names of the model's inputs: [`TimeFunction::Input`](dalembert_system::TimeFunction)
    /// `k` is `inputs[k]`, set by a [`crate::Simulator`] (0 in a run from start to end).
    pub inputs: Vec<String>,
    /// The names of the model's code forces (`type = "code"`): element `k` asks the
    /// [`crate::Simulator`]'s function `k` for its wrench (nothing in a run from start to end).
    pub code_forces: Vec<String>,
}

impl Simulation {
    /// Assembles the initial state: position analysis from the given `q` (least change), then the
    /// least (weighted) change to `q̇` that satisfies the velocity constraints.
    pub fn assemble(&mut self) -> Result<(), SimulationError> {
        assemble(
            self.model.as_system(),
            self.start,
            &mut self.q,
            &mut self.qd,
            self.velocity_weights.as_deref(),
        )?;
        Ok(())
    }

    /// Builds the chosen formulation on the model (in its absolute coordinates).
    pub fn formulation(&self) -> Result<Box<dyn Formulation>, SimulationError> {
        self.formulation_on(self.model.system(), self.independent.clone())
    }

    /// Builds the chosen formulation on `system` (the model, or its joint coordinates), with the
    /// embedding formulation's `independent` velocity indices of that system.
    pub(crate) fn formulation_on(
        &self,
        system: Arc<dyn MultibodySystem>,
        independent: Option<Vec<usize>>,
    ) -> Result<Box<dyn Formulation>, SimulationError> {
        self.build_on(system, independent, true)
    }

    /// The chosen formulation on the model (absolute coordinates) without the switching law of
    /// its friction and limits: what a joint-coordinate run's samples are evaluated with, the
    /// run's limit forces added ([`crate::joint_map`]).
    pub(crate) fn formulation_without_switching(&self) -> Result<Box<dyn Formulation>, SimulationError> {
        self.build_on(self.model.system(), self.independent.clone(), false)
    }

    fn build_on(
        &self,
        system: Arc<dyn MultibodySystem>,
        independent: Option<Vec<usize>>,
        switching: bool,
    ) -> Result<Box<dyn Formulation>, SimulationError> {
        // The embedding and amalgamated formulations still partition the coordinates on a dense
        // C_q (m × n) and both store B_i by rows (n × dof) and the reduced mass matrix (dof ×
        // dof): refuse models whose dense matrices would not fit, naming the size, instead of
        // failing in the allocator.
        let entry = self.formulation.entry();
        let (n, m) = (system.layout().n_v(), system.num_equations());
        let too_large = if !entry.dense_partitioning {
            None
        } else if !dense_fits(m, n) {
            Some((m, n))
        } else if !dense_fits(n, n.saturating_sub(m)) {
            Some((n, n - m))
        } else {
            None
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
        let settings = FormulationSettings {
            redundancy: self.redundancy,
            independent,
        };
        let model = self.model.system();
        let Some((joint, kind)) = switching_joint(model.as_ref()).filter(|_| switching) else {
            return Ok((entry.build)(system, &settings)?);
        };
        let refuse = |what: String| {
            SimulationError::Setup(DynamicsError::Friction {
                time: self.start,
                joint: joint.clone(),
                what,
            })
        };
        if system.frictions().len() != model.frictions().len() || system.limits().len() != model.limits().len() {
            return Err(refuse(format!(
                "joint {kind} is solved in absolute coordinates only: use coordinates = \"absolute\""
            )));
        }
        let method = self.integrator.method.entry();
        if method.applies == dalembert_integrators::Applies::AugmentedIndex3 {
            if kind == "friction" {
                return Err(refuse(format!(
                    "{} integrates the index-3 equations without joint {kind}: use rk4 or dopri5",
                    method.name
                )));
            }
            // Limits: free while no joint reaches a bound; the run stops where one does.
            return Ok(Box::new(
                dalembert_system::Frictional::new((entry.build)(system, &settings)?)?.refusing_impacts_because(
                    &format!(
                        "{} integrates the index-3 equations without stops: it runs while every limit is free and stops here; use rk4 or dopri5, which take the impacts",
                        method.name
                    ),
                ),
            ));
        }
        Ok(Box::new(dalembert_system::Frictional::new((entry.build)(
            system, &settings,
        )?)?))
    }

    /// Runs from the current initial state, handing every output sample to `observer`. Where
    /// the model's forces switch (contacts, friction, limits), each sample carries the work
    /// integrated along the run's steps ([`dalembert_integrators::Sample::work`]), so that
    /// [`crate::energy::EnergyBalance`] does not depend on the output interval.
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
        if self.coordinates == Coordinates::Joint {
            return self.run_in_joint_coordinates(observer, cancel);
        }
        let mut f = self.formulation()?;
        Ok(integrate_cancellable(
            f.as_mut(),
            self.start,
            self.end,
            &self.q,
            &self.qd,
            &self.integrator.with_work_along_steps(true),
            observer,
            cancel,
        )?)
    }

    /// [`Simulation::run_cancellable`] in joint coordinates: the tree from the current (assembled)
    /// state, integrated with the chosen formulation and method; each output sample mapped back
    /// to the model's coordinates, with `q̈`, `λ` and the residuals of the model's own formulation
    /// there (one evaluation per sample). `cancel` is read at every output sample. A failure of
    /// that evaluation stops the run at the sample, with the error and the statistics so far.
    fn run_in_joint_coordinates(
        &self,
        observer: &mut dyn FnMut(&Sample<'_>),
        cancel: &AtomicBool,
    ) -> Result<Statistics, SimulationError> {
        let JointStart {
            mut map,
            formulation: mut f,
            q0,
            qd0,
        } = JointMap::start(self, &self.q, &self.qd)?;
        let (stop, mut failed) = (AtomicBool::new(false), None);
        let (mut violation, mut velocity_violation) = (0.0f64, 0.0f64);
        let result = integrate_cancellable(
            f.as_mut(),
            self.start,
            self.end,
            &q0,
            &qd0,
            &self.integrator.with_work_along_steps(true),
            &mut |s| {
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                match map.sample(s) {
                    Ok(sample) => {
                        violation = violation.max(sample.constraint_violation);
                        velocity_violation = velocity_violation.max(sample.velocity_violation);
                        observer(&sample);
                    }
                    Err(e) => {
                        failed = Some(e);
                        stop.store(true, Ordering::Relaxed);
                        return;
                    }
                }
                if cancel.load(Ordering::Relaxed) {
                    stop.store(true, Ordering::Relaxed);
                }
            },
            &stop,
        );
        let with_violations = |mut st: Statistics| {
            st.max_constraint_violation = violation;
            st.max_velocity_violation = velocity_violation;
            st
        };
        // A failed evaluation at a sample is the run's outcome, even at the last sample (after
        // which the integration itself ends without error).
        let failure = |error, st: Statistics| {
            Err(SimulationError::Integration(IntegrationFailure {
                error,
                statistics: Box::new(with_violations(st)),
            }))
        };
        match (result, failed) {
            (Ok(st), None) => Ok(with_violations(st)),
            (Ok(st), Some(cause)) => failure(IntegrationError::Dynamics(cause), st),
            (Err(e), Some(cause)) => failure(IntegrationError::Dynamics(cause), *e.statistics),
            (Err(e), None) => failure(e.error, *e.statistics),
        }
    }
}

/// Assembles `(q, q̇)` to the constraints of `system` at `t`: the least change of the positions
/// (Newton with minimum-norm steps), then of the velocities weighted by `weights` (per velocity
/// coordinate; `None`: the mass matrix's diagonal). The one assembly of scenes, simulations and
/// simulators.
pub(crate) fn assemble(
    system: &dyn MultibodySystem,
    t: f64,
    q: &mut [f64],
    qd: &mut [f64],
    weights: Option<&[f64]>,
) -> Result<(), ConstraintError> {
    let opts = KinematicOptions::default();
    let sys = system.constraints();
    sys.solve_positions(t, q, &opts)?;
    sys.solve_velocities_weighted(t, q, qd, weights, &opts)
}

/// The first joint or contact of `system` with friction or limits, as `joint 'NAME'` or `contact
/// 'NAME'`, and which (`"friction"` or `"limits"`): a model whose law switches at events
/// (`docs/friction.md`, `docs/limits.md`).
pub(crate) fn switching_joint(system: &dyn dalembert_system::MultibodySystem) -> Option<(String, &'static str)> {
    if let Some(f) = system.frictions().first() {
        return Some((format!("{} '{}'", f.element, f.name), "friction"));
    }
    system
        .limits()
        .first()
        .map(|l| (format!("{} '{}'", l.element, l.name), "limits"))
}

#[cfg(test)]
mod formulation_names {
    use super::FormulationKind;

    /// The names, the list and the parser agree: each name parses back to its formulation, and
    /// nothing else does.
    #[test]
    fn names_parse_back() {
        assert_eq!(FormulationKind::NAMES, ["augmented", "embedding", "amalgamated"]);
        for k in FormulationKind::ALL {
            assert_eq!(FormulationKind::parse(k.name()), Some(k));
        }
        assert_eq!(FormulationKind::parse("Augmented"), None);
        assert_eq!(FormulationKind::parse(""), None);
    }
}
