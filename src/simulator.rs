//! A model driven step by step from the caller's code: [`Simulator`].
//!
//! A simulator is a run ([`dalembert_integrators::Integration`]) of a [`Simulation`]'s formulation
//! and method that the caller advances ([`Simulator::step`], [`Simulator::advance_to`]) and drives
//! between steps through the model's named inputs ([`Simulator::set_input`]: held until set again,
//! 0 before the first set). It reads any output column at the current time
//! ([`Simulator::value`], the CSV's names) and can be put in another state
//! ([`Simulator::set_state`]) or back at the start ([`Simulator::reset`]).
//!
//! The run's steps do not depend on where the caller stops it: advanced in any chunks it is the
//! same run, bitwise, as one advanced to the end at once, and as [`Simulation::run`] (same method,
//! same step). Stopped between two steps, it shows the state there from the step across it (dense
//! output, or the Hermite interpolant of a fixed step); setting an input or a state there makes
//! that state the run's own, and the steps go on from it. Stepping allocates nothing.
//!
//! ```
//! // A slider pushed by a named input: a proportional-derivative controller in the loop.
//! let text = r#"
//! [[bodies]]
//! name = "slider"
//! mass = 2.0
//! inertia = 0.1
//! position = [0.0, 0.0]
//! [[joints]]
//! name = "guide"
//! type = "prismatic"
//! bodies = ["ground", "slider"]
//! at = [0.0, 0.0]
//! axis = [1.0, 0.0]
//! [[forces]]
//! name = "push"
//! type = "force"
//! body = "slider"
//! fx = { input = "push" }
//! [simulation]
//! integrator = "rk4"
//! step = 1e-3
//! "#;
//! let scene = dalembert::Scene::from_toml(text, "pushed slider")?;
//! let mut sim = scene.simulator()?;
//! assert_eq!(sim.inputs(), ["push"]);
//! for k in 1..=2000 {
//!     let (x, v) = (sim.value("slider.x")?, sim.value("slider.vx")?);
//!     sim.set_input("push", 40.0 * (1.0 - x) - 12.0 * v)?; // toward x = 1
//!     sim.advance_to(k as f64 * 0.005)?;
//! }
//! assert!((sim.time() - 10.0).abs() < 1e-12);
//! assert!((sim.value("slider.x")? - 1.0).abs() < 1e-6, "the controller holds the slider at x = 1");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use crate::joint_map::{JointMap, JointStart};
use crate::output::Rows;
use crate::scene::unknown_name;
use crate::simulation::{Coordinates, Simulation, SimulationError};
use dalembert_integrators::{Integration, IntegrationError, IntegrationFailure, Statistics};
use dalembert_system::inputs::{with_code_forces, with_inputs, BodyMotion, Wrench};
use dalembert_system::Shortest;
use dalembert_system::{ConstraintError, Formulation, KinematicOptions};
use std::cell::RefCell;
use std::sync::atomic::AtomicBool;
use thiserror::Error;

/// Why a simulator refused a request or could not go on. After a refused request (an unknown
/// name, a bad value, a time in the past, a state of the wrong size or one that cannot be
/// assembled) the simulator is unchanged and usable.
#[derive(Debug, Error)]
pub enum SimulatorError {
    /// The simulator could not be built, or the run failed (a numerical failure, an interrupt).
    #[error(transparent)]
    Simulation(#[from] SimulationError),
    /// No input of that name.
    #[error("{}", unknown_input(.name, .inputs))]
    UnknownInput {
        /// The name asked for.
        name: String,
        /// The model's inputs.
        inputs: Vec<String>,
    },
    /// No code force of that name.
    #[error("{}", unknown_code_force(.name, .forces))]
    UnknownCodeForce {
        /// The name asked for.
        name: String,
        /// The model's code forces.
        forces: Vec<String>,
    },
    /// An input value that is NaN or infinite.
    #[error("input '{name}': {value} is not a finite value")]
    NonFiniteInput {
        /// The input.
        name: String,
        /// The value refused.
        value: f64,
    },
    /// No output column of that name.
    #[error("{}", unknown_name("column", .name, &.columns.iter().map(String::as_str).collect::<Vec<_>>()))]
    UnknownColumn {
        /// The name asked for.
        name: String,
        /// The output's columns.
        columns: Vec<String>,
    },
    /// A time before the simulator's (or not finite).
    #[error("cannot advance to t = {}: the simulator is at t = {} and goes forward only", Shortest(*.to), Shortest(*.at))]
    Past {
        /// The time asked for.
        to: f64,
        /// The simulator's time.
        at: f64,
    },
    /// A state of the wrong size, or with a coordinate that is not finite (named).
    #[error("set_state: {0}")]
    State(String),
    /// A state that cannot be assembled to the constraints.
    #[error("set_state: the state cannot be assembled to the constraints: {0}")]
    Assembly(#[source] ConstraintError),
}

fn unknown_input(name: &str, inputs: &[String]) -> String {
    if inputs.is_empty() {
        return format!("unknown input '{name}': the model has no inputs (a function {{ input = \"NAME\" }} in a scene declares one)");
    }
    let names: Vec<&str> = inputs.iter().map(String::as_str).collect();
    unknown_name("input", name, &names)
}

fn unknown_code_force(name: &str, forces: &[String]) -> String {
    if forces.is_empty() {
        return format!("unknown code force '{name}': the model has none (a force element of type \"code\" in a scene declares one)");
    }
    let names: Vec<&str> = forces.iter().map(String::as_str).collect();
    unknown_name("code force", name, &names)
}

/// How far [`Simulator::set_state`] moved the given state to satisfy the constraints: the largest
/// change of a position and of a velocity.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Moved {
    /// `‖q_assembled − q_given‖∞`.
    pub positions: f64,
    /// `‖q̇_assembled − q̇_given‖∞`.
    pub velocities: f64,
}

/// The function of a code force: time and the body's motion to its wrench.
pub type ForceFn = Box<dyn FnMut(f64, &BodyMotion) -> Wrench + Send>;

/// The functions of the model's code forces (`None`: not set, nothing applied).
struct Forces(RefCell<Vec<Option<ForceFn>>>);

impl Forces {
    /// The wrench of code force `k`.
    fn call(&self, k: usize, t: f64, motion: &BodyMotion) -> Wrench {
        match self.0.borrow_mut().get_mut(k) {
            Some(Some(f)) => f(t, motion),
            _ => Wrench::default(),
        }
    }
}

/// Runs `f` with the simulator's inputs and code forces lent to the model's evaluations.
fn lent<R>(values: &[f64], forces: &Forces, f: impl FnOnce() -> R) -> R {
    with_inputs(values, || with_code_forces(&|k, t, m| forces.call(k, t, m), f))
}

/// A model driven step by step (see the module documentation).
pub struct Simulator {
    simulation: Simulation,
    formulation: Box<dyn Formulation>,
    run: Integration,
    values: Vec<f64>,
    forces: Forces,
    rows: Rows,
    row: Vec<f64>,
    row_valid: bool,
    /// In joint coordinates: the map to the model's coordinates (the run integrates the tree).
    joint: Option<JointMap>,
    /// The statistics of the runs a state set in joint coordinates replaced.
    before: Option<Statistics>,
}

impl std::fmt::Debug for Simulator {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Simulator")
            .field("t", &self.time())
            .field("inputs", &self.simulation.inputs)
            .field("values", &self.values)
            .finish_non_exhaustive()
    }
}

impl Simulation {
    /// A simulator of this simulation: its formulation and method from its (assembled) initial
    /// state at its start time, inputs at 0. `end` sets the output grid a fixed-step method
    /// spans ([`Simulation::run`]'s); the simulator may go beyond it.
    pub fn simulator(&self) -> Result<Simulator, SimulatorError> {
        Simulator::new(self.clone())
    }
}

impl crate::Scene {
    /// A simulator of this scene with its settings ([`crate::Scene::simulation`]).
    pub fn simulator(&self) -> Result<Simulator, SimulatorError> {
        self.simulation().simulator()
    }
}

impl Simulator {
    fn new(simulation: Simulation) -> Result<Self, SimulatorError> {
        let values = vec![0.0; simulation.inputs.len()];
        let forces = Forces(RefCell::new(simulation.code_forces.iter().map(|_| None).collect()));
        let (formulation, run, joint) = start(
            &simulation,
            simulation.start,
            &simulation.q,
            &simulation.qd,
            &values,
            &forces,
        )?;
        let rows = Rows::new(&simulation.model);
        let row = Vec::with_capacity(rows.names().len());
        Ok(Simulator {
            simulation,
            formulation,
            run,
            values,
            forces,
            rows,
            row,
            row_valid: false,
            joint,
            before: None,
        })
    }

    /// The model's input names (a scene's `{ input = "NAME" }`).
    pub fn inputs(&self) -> &[String] {
        &self.simulation.inputs
    }

    fn input_index(&self, name: &str) -> Result<usize, SimulatorError> {
        self.simulation
            .inputs
            .iter()
            .position(|n| n == name)
            .ok_or_else(|| SimulatorError::UnknownInput {
                name: name.to_string(),
                inputs: self.simulation.inputs.clone(),
            })
    }

    /// Sets input `name` to `value` from the current time on (held until set again). Between two
    /// steps (after [`Simulator::advance_to`] stopped inside one) the state shown becomes the
    /// run's own first, so the new value acts from exactly this time.
    pub fn set_input(&mut self, name: &str, value: f64) -> Result<(), SimulatorError> {
        let k = self.input_index(name)?;
        if !value.is_finite() {
            return Err(SimulatorError::NonFiniteInput {
                name: name.to_string(),
                value,
            });
        }
        if self.values[k] != value {
            self.run.commit();
            self.values[k] = value;
            self.row_valid = false;
        }
        Ok(())
    }

    /// The value input `name` holds.
    pub fn input(&self, name: &str) -> Result<f64, SimulatorError> {
        Ok(self.values[self.input_index(name)?])
    }

    /// The model's code forces (a scene's `type = "code"` elements).
    pub fn code_forces(&self) -> &[String] {
        &self.simulation.code_forces
    }

    /// Computes code force `name` with `f` from now on: at every stage of every step, `f(t,
    /// motion)` gives the force at the body's centre of mass and the torque, global components
    /// ([`crate::code_force`]). It must not allocate if the stepping is to allocate nothing, and
    /// it is called only from the thread that steps. Between two steps the state shown becomes the
    /// run's own first, as for an input.
    pub fn set_force(
        &mut self,
        name: &str,
        f: impl FnMut(f64, &BodyMotion) -> Wrench + Send + 'static,
    ) -> Result<(), SimulatorError> {
        let Some(k) = self.simulation.code_forces.iter().position(|n| n == name) else {
            return Err(SimulatorError::UnknownCodeForce {
                name: name.to_string(),
                forces: self.simulation.code_forces.clone(),
            });
        };
        self.run.commit();
        self.forces.0.borrow_mut()[k] = Some(Box::new(f));
        self.row_valid = false;
        Ok(())
    }

    /// The current time.
    pub fn time(&self) -> f64 {
        self.run.time()
    }

    /// The current state `(q, q̇)` in the model's coordinates (in joint coordinates too: the
    /// tree's state mapped to the bodies).
    pub fn state(&self) -> (&[f64], &[f64]) {
        match &self.joint {
            Some(map) => map.state(),
            None => self.run.state(),
        }
    }

    /// One step of the method (an adaptive method: one accepted step); after
    /// [`Simulator::advance_to`] stopped between two steps, to the end of the step in progress.
    pub fn step(&mut self) -> Result<(), SimulatorError> {
        self.drive(|run, f| run.step(f, &AtomicBool::new(false)))
    }

    /// Advances to exactly `t` (see the module documentation).
    pub fn advance_to(&mut self, t: f64) -> Result<(), SimulatorError> {
        self.advance_to_cancellable(t, &AtomicBool::new(false))
    }

    /// [`Simulator::advance_to`] that stops after the step during which `cancel` was set (e.g.
    /// by a Ctrl-C handler) with an interrupted-run error carrying the time; the simulator is
    /// then at that step and can go on.
    pub fn advance_to_cancellable(&mut self, t: f64, cancel: &AtomicBool) -> Result<(), SimulatorError> {
        let at = self.time();
        if !t.is_finite() || t < at {
            return Err(SimulatorError::Past { to: t, at });
        }
        self.drive(|run, f| run.advance_to(f, t, cancel))
    }

    /// Runs `work` on the run and its formulation with the inputs and code forces lent to the
    /// model; a failure is the run's, with its statistics so far.
    fn drive(
        &mut self,
        work: impl FnOnce(&mut Integration, &mut dyn Formulation) -> Result<(), IntegrationError>,
    ) -> Result<(), SimulatorError> {
        self.row_valid = false;
        let Simulator {
            formulation,
            run,
            values,
            forces,
            joint,
            before,
            ..
        } = self;
        let result = lent(values, forces, || work(run, formulation.as_mut()));
        if let Some(map) = joint {
            let (q, qd) = run.state();
            map.map(q, qd);
        }
        result.map_err(|error| failure(error, then(before, run.statistics(formulation.as_ref()))))
    }

    /// The output columns [`Simulator::value`] reads (those of the CSV, `t` first).
    pub fn columns(&self) -> &[String] {
        self.rows.names()
    }

    /// The output row at the current time: every column of [`Simulator::columns`]. Accelerations,
    /// multipliers and reactions are evaluated once per time (later reads are free).
    pub fn row(&mut self) -> Result<&[f64], SimulatorError> {
        if !self.row_valid {
            let Simulator {
                formulation,
                run,
                values,
                forces,
                rows,
                row,
                joint,
                before,
                ..
            } = self;
            let sample = lent(values, forces, || {
                let s = run.sample(formulation.as_mut())?;
                row.clear();
                match joint {
                    Some(map) => rows.push(&map.sample(&s)?, row),
                    None => rows.push(&s, row),
                }
                Ok(())
            });
            if let Err(error) = sample {
                return Err(failure(error, then(before, run.statistics(formulation.as_ref()))));
            }
            self.row_valid = true;
        }
        Ok(&self.row)
    }

    /// The value of output column `column` (a CSV column name: `slider.x`, `guide.fy`,
    /// `motor.effort`, `energy`, …) at the current time.
    pub fn value(&mut self, column: &str) -> Result<f64, SimulatorError> {
        let Some(k) = self.rows.names().iter().position(|c| c == column) else {
            return Err(SimulatorError::UnknownColumn {
                name: column.to_string(),
                columns: self.rows.names().to_vec(),
            });
        };
        Ok(self.row()?[k])
    }

    /// Puts the simulator in state `(q, q̇)` at the current time: assembled to the constraints
    /// first (the least change of the positions, then of the velocities), and the method started
    /// again from there. Returns how far the assembly moved the state.
    pub fn set_state(&mut self, q: &[f64], qd: &[f64]) -> Result<Moved, SimulatorError> {
        let (n_q, n_v) = (self.simulation.q.len(), self.simulation.qd.len());
        if q.len() != n_q || qd.len() != n_v {
            return Err(SimulatorError::State(format!(
                "the model has {n_q} positions and {n_v} velocities; {} and {} were given",
                q.len(),
                qd.len()
            )));
        }
        let (q_columns, v_columns) = self.rows.state_columns(&self.simulation.model);
        let names = self.rows.names();
        for (x, &k) in q.iter().zip(&q_columns).chain(qd.iter().zip(&v_columns)) {
            let name = &names[k];
            if !x.is_finite() {
                return Err(SimulatorError::State(format!("{name} = {x} is not finite")));
            }
        }
        let t = self.time();
        let (mut q_new, mut qd_new) = (q.to_vec(), qd.to_vec());
        let opts = KinematicOptions::default();
        let sys = self.simulation.model.as_system().constraints();
        lent(&self.values, &self.forces, || -> Result<(), ConstraintError> {
            sys.solve_positions(t, &mut q_new, &opts)?;
            sys.solve_velocities_weighted(t, &q_new, &mut qd_new, None, &opts)?;
            Ok(())
        })
        .map_err(SimulatorError::Assembly)?;
        let largest = |a: &[f64], b: &[f64]| a.iter().zip(b).fold(0.0f64, |m, (x, y)| m.max((x - y).abs()));
        let moved = Moved {
            positions: largest(&q_new, q),
            velocities: largest(&qd_new, qd),
        };
        if self.joint.is_some() {
            // The tree is built again with its zero configuration at the new state.
            let stats = self.statistics();
            let (formulation, run, joint) = start(&self.simulation, t, &q_new, &qd_new, &self.values, &self.forces)?;
            (self.formulation, self.run, self.joint) = (formulation, run, joint);
            self.before = Some(stats);
            self.row_valid = false;
        } else {
            self.drive(|run, f| run.set_state(f, &q_new, &qd_new))?;
        }
        Ok(moved)
    }

    /// Sets every velocity to zero where the run is, in the coordinates it integrates (joint
    /// coordinates too, without assembling the model again as [`Simulator::set_state`] does):
    /// zero rates satisfy every joint's velocity equations. For the kinetic damping of
    /// [`crate::relaxation`].
    pub(crate) fn stop_motion(&mut self) -> Result<(), SimulatorError> {
        let (q, qd) = self.run.state();
        let (q, zero) = (q.to_vec(), vec![0.0; qd.len()]);
        self.drive(|run, f| run.set_state(f, &q, &zero))
    }

    /// Back to the initial state at the start time, inputs at 0, as newly built; the code
    /// forces keep their functions.
    pub fn reset(&mut self) -> Result<(), SimulatorError> {
        let mut fresh = Simulator::new(self.simulation.clone())?;
        std::mem::swap(&mut fresh.forces, &mut self.forces);
        *self = fresh;
        Ok(())
    }

    /// The run's statistics so far.
    pub fn statistics(&self) -> Statistics {
        then(&self.before, self.run.statistics(self.formulation.as_ref()))
    }

    /// The simulation the simulator was built from (its model, initial state and settings).
    pub fn simulation(&self) -> &Simulation {
        &self.simulation
    }
}

/// A run started: its formulation, the run, and the map from joint coordinates.
type Started = (Box<dyn Formulation>, Integration, Option<JointMap>);

/// The formulation and the run of `simulation` from `(t, q, q̇)` (assembled), with the map from
/// joint coordinates when it runs in them (the tree's zero configuration at that state).
fn start(
    simulation: &Simulation,
    t: f64,
    q: &[f64],
    qd: &[f64],
    values: &[f64],
    forces: &Forces,
) -> Result<Started, SimulatorError> {
    let (mut formulation, q0, qd0, mut joint) = if simulation.coordinates == Coordinates::Joint {
        let s: JointStart = JointMap::start(simulation, q, qd)?;
        (s.formulation, s.q0, s.qd0, Some(s.map))
    } else {
        (simulation.formulation()?, q.to_vec(), qd.to_vec(), None)
    };
    // The output grid of a fixed-step method spans the simulation's; a run started again at or
    // past its end has one output interval.
    let end = if t < simulation.end {
        simulation.end
    } else {
        t + simulation.integrator.output_every
    };
    let run = lent(values, forces, || {
        Integration::new(formulation.as_mut(), t, end, &q0, &qd0, &simulation.integrator)
    })
    .map_err(|error| failure(error, Statistics::default()))?;
    if let Some(map) = &mut joint {
        let (q, qd) = run.state();
        map.map(q, qd);
    }
    Ok((formulation, run, joint))
}

/// The statistics of a run after `before` (the runs a state set in joint coordinates replaced).
fn then(before: &Option<Statistics>, now: Statistics) -> Statistics {
    match before {
        Some(b) => b.then(&now),
        None => now,
    }
}

/// A run's failure as a simulation error, with the statistics so far.
fn failure(error: IntegrationError, statistics: Statistics) -> SimulatorError {
    SimulatorError::Simulation(SimulationError::Integration(IntegrationFailure {
        error,
        statistics: Box::new(statistics),
    }))
}
