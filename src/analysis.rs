//! The analyses a scene offers besides simulation, as data: the structure check with the initial
//! accelerations and reactions ([`Scene::check`]), inverse dynamics over a time grid
//! ([`Scene::inverse`]) and a simulation kept in memory ([`Scene::record`]). The command line and
//! the Python package print or convert these; neither computes anything of its own.

use crate::output::{Recorder, Rows, Table};
use crate::simulation::SimulationError;
use crate::Mechanism;
use crate::Scene;
use dalembert_augmented::InverseDynamics;
use dalembert_integrators::{Sample, Statistics};
use dalembert_system::StructureReport;
use dalembert_system::{ConstraintError, ConstraintSet, ConstraintValues};
use dalembert_system::{DynamicsError, KinematicOptions, RedundancyTreatment};
use std::sync::atomic::AtomicBool;

/// What [`Scene::check`] finds: the structure of the constraints at the assembled configuration,
/// and the accelerations and reactions at t = 0.
#[derive(Debug, Clone, PartialEq)]
pub struct CheckReport {
    /// The scene's name.
    pub scene: String,
    /// Moving bodies.
    pub bodies: usize,
    /// Coordinates `n`.
    pub coordinates: usize,
    /// Constraint equations `m`.
    pub equations: usize,
    /// Numerical rank of `C_q`.
    pub rank: usize,
    /// Degrees of freedom `n − rank`.
    pub degrees_of_freedom: usize,
    /// The redundant equations, named (`joint 'B' equation 2`).
    pub redundant: Vec<String>,
    /// True when the scene asks for the minimum-norm treatment of redundant equations.
    pub minimum_norm: bool,
    /// Largest `|C|` of the assembled configuration.
    pub max_violation: f64,
    /// Coordinate names (`crank.x`, `crank.y`, `crank.angle`, …), in the order of
    /// [`CheckReport::accelerations`].
    pub coordinate_names: Vec<String>,
    /// `q̈` at t = 0, or why it could not be computed.
    pub accelerations: Result<Vec<f64>, String>,
    /// The reaction and effort columns of the output (`O.fx`, `motor.effort`, …) and their
    /// values at t = 0 (empty when the accelerations failed).
    pub reactions: Vec<(String, f64)>,
}

impl CheckReport {
    /// The problems that make the scene unfit to run as written (empty when it can run).
    pub fn problems(&self) -> Vec<String> {
        let mut problems = Vec::new();
        if !self.redundant.is_empty() && !self.minimum_norm {
            problems.push(format!(
                "{} redundant constraint equation(s): {} (set `redundant = \"minimum-norm\"` in [simulation] or pass --redundant minimum-norm to solve with minimum-norm reactions)",
                self.redundant.len(),
                self.redundant.join(", ")
            ));
        }
        if let Err(e) = &self.accelerations {
            problems.push(format!("initial accelerations: {e}"));
        }
        problems
    }
}

/// A simulation kept in memory: every output row, and the statistics or the failure (the rows
/// before a failure are kept).
#[derive(Debug)]
pub struct Recording {
    /// The output rows, with the columns of [`crate::output`].
    pub table: Table,
    /// Statistics of a finished run, or why it stopped (the statistics up to then inside).
    pub outcome: Result<Statistics, SimulationError>,
    /// The energy warning of a conservative model whose `T + V` changed by more than
    /// [`crate::ENERGY_WARNING_FRACTION`] of its energy scale ([`crate::energy_warning`]).
    pub warning: Option<String>,
}

/// The rank tolerance of the structure analysis: singular values of `C_q` below this share of
/// the largest count as zero.
const RANK_TOLERANCE: f64 = 1e-9;

/// The structure of the constraints whose values at a state are `values` (the one call of the
/// analysis for scenes, their checks and the command line).
fn structure_of(sys: &dyn ConstraintSet, values: &ConstraintValues) -> Result<StructureReport, ConstraintError> {
    sys.analyse_structure(values, RANK_TOLERANCE)
}

/// The structure of `model`'s constraints at positions `q`, time 0: rank, degrees of freedom and
/// redundant equations.
pub(crate) fn structure_at(model: &Mechanism, q: &[f64]) -> Result<StructureReport, ConstraintError> {
    let sys = model.as_system().constraints();
    let mut values = sys.values();
    sys.evaluate(0.0, q, &[], &mut values);
    structure_of(sys, &values)
}

impl Scene {
    /// The structure of the scene's constraints at its initial positions: rank, degrees of
    /// freedom, redundant equations by name.
    pub fn structure(&self) -> Result<StructureReport, ConstraintError> {
        structure_at(&self.model, &self.q)
    }

    /// The structure check of `dalembert check`: degrees of freedom, redundant equations named,
    /// the assembled violation, and the accelerations and reactions at t = 0 with the scene's
    /// formulation. Errors only when the structure analysis itself cannot run (a model too large
    /// for it, named).
    pub fn check(&self) -> Result<CheckReport, SimulationError> {
        let model = &self.model;
        let sys = model.as_system().constraints();
        let mut vals = sys.values();
        sys.evaluate(0.0, &self.q, &self.qd, &mut vals);
        let s = structure_of(sys, &vals)?;
        let mut rows = Rows::new(model);
        let coordinate_names = model.velocity_names();
        let (n, m) = (model.num_velocities(), model.num_equations());
        let (mut qdd, mut lam) = (vec![0.0; n], vec![0.0; m]);
        // The friction and limit forces of that evaluation (joints' friction, stops and rigid
        // contacts held at the start).
        let (mut friction, mut limit) = (Vec::new(), Vec::new());
        let accelerations = self
            .simulation()
            .formulation()
            .map_err(|e| e.to_string())
            .and_then(|mut f| {
                f.accelerations(0.0, &self.q, &self.qd, None, &mut qdd, &mut lam)
                    .map_err(|e| e.to_string())?;
                friction = f.friction_forces().to_vec();
                limit = f.limit_forces().to_vec();
                Ok(())
            });
        let reactions = match accelerations {
            Ok(()) => {
                // The reaction columns of an output row at t = 0.
                let sample = Sample {
                    t: 0.0,
                    q: &self.q,
                    qd: &self.qd,
                    qdd: &qdd,
                    lambda: &lam,
                    friction: &friction,
                    limit: &limit,
                    impact_loss: 0.0,
                    work: f64::NAN,
                    constraint_violation: 0.0,
                    velocity_violation: 0.0,
                    energy: 0.0,
                };
                let mut row = Vec::new();
                rows.push(&sample, &mut row);
                let columns = rows.reaction_columns();
                rows.names()[columns.clone()]
                    .iter()
                    .cloned()
                    .zip(row[columns].iter().copied())
                    .collect()
            }
            Err(_) => Vec::new(),
        };
        Ok(CheckReport {
            scene: self.name.clone(),
            bodies: model.num_bodies(),
            coordinates: s.coordinates,
            equations: s.equations,
            rank: s.rank,
            degrees_of_freedom: s.degrees_of_freedom,
            redundant: s.redundant.iter().map(|e| e.to_string()).collect(),
            minimum_norm: self.settings.redundancy == RedundancyTreatment::MinimumNorm,
            max_violation: vals.c.iter().fold(0.0f64, |a, v| a.max(v.abs())),
            coordinate_names,
            accelerations: accelerations.map(|()| qdd),
            reactions,
        })
    }

    /// Simulates with the scene's settings and keeps every output row in memory. `cancel` stops
    /// the run after the current step (the rows so far are kept). The warning is `simulate`'s:
    /// a conservative model's energy, or another's energy balance `E − W`
    /// ([`crate::energy::EnergyBalance`]), changed by more than
    /// [`crate::ENERGY_WARNING_FRACTION`] of its energy scale.
    pub fn record(&self, cancel: &AtomicBool) -> Recording {
        let sim = self.simulation();
        let model = self.model.as_system();
        let mut rec = Recorder::new(&self.model);
        let mut balance = (!model.is_conservative()).then(|| crate::energy::EnergyBalance::new(model));
        let outcome = sim.run_cancellable(
            &mut |s| {
                if let Some(b) = balance.as_mut() {
                    b.push(model, s);
                }
                rec.record(s)
            },
            cancel,
        );
        let warning = match (&outcome, &balance) {
            (Ok(st), Some(b)) => crate::energy_warning(b.largest_drift(), st.energy_scale, true),
            _ => self.energy_warning_of(&outcome),
        };
        Recording {
            table: rec.into_table(),
            outcome,
            warning,
        }
    }

    /// The energy warning of a finished run of this scene: a conservative model whose `T + V`
    /// changed by more than [`crate::ENERGY_WARNING_FRACTION`] of its energy scale.
    pub(crate) fn energy_warning_of(&self, outcome: &Result<Statistics, SimulationError>) -> Option<String> {
        match outcome {
            Ok(st) if self.model.as_system().is_conservative() => {
                crate::energy_warning(st.max_energy_change, st.energy_scale, false)
            }
            _ => None,
        }
    }

    /// Inverse dynamics of a fully driven scene on the grid `0, every, 2 every, …, end`: each
    /// sample (positions, velocities, accelerations and multipliers from the drivers) is handed to
    /// `observer`, whose reactions and efforts follow from the multipliers as in a simulation
    /// (drivers' columns `<driver>.effort`). Stops at the first time the kinematics fail.
    pub fn inverse(&self, end: f64, every: f64, observer: &mut dyn FnMut(&Sample<'_>)) -> Result<(), DynamicsError> {
        if !(end.is_finite() && end > 0.0 && every.is_finite() && every > 0.0) {
            return Err(DynamicsError::Singular {
                time: 0.0,
                what: format!("inverse dynamics needs a positive end and interval, got end {end}, every {every}"),
            });
        }
        let model = self.model.as_system();
        let inv = InverseDynamics::new(self.model.system(), &self.q, KinematicOptions::default())?;
        let sys = model.constraints();
        let steps = (end / every - 1e-9).ceil() as usize;
        let mut cd = vec![0.0; model.num_equations()];
        let mut vals = sys.values();
        let inf = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let mut prev: Option<dalembert_augmented::InverseSolution> = None;
        for i in 0..=steps {
            let t = (i as f64 * every).min(end);
            // Continuation from the previous instant keeps the motion on its branch.
            let sol = match &prev {
                None => inv.solve(t, &self.q)?,
                Some(p) => inv.advance(p, t)?,
            };
            sys.evaluate(t, &sol.q, &sol.qd, &mut vals);
            sys.velocity_residual(&vals, &sol.qd, &mut cd);
            observer(&Sample {
                t,
                q: &sol.q,
                qd: &sol.qd,
                qdd: &sol.qdd,
                lambda: &sol.lambda,
                friction: &[],
                limit: &[],
                impact_loss: 0.0,
                work: f64::NAN,
                constraint_violation: inf(&vals.c),
                velocity_violation: inf(&cd),
                energy: model.kinetic_energy(&sol.q, &sol.qd) + model.potential_energy(t, &sol.q),
            });
            prev = Some(sol);
        }
        Ok(())
    }

    /// [`Scene::inverse`] kept in memory: the rows (output columns, driver efforts included) and
    /// the failure, if any, after the rows computed before it.
    pub fn inverse_table(&self, end: f64, every: f64) -> (Table, Result<(), DynamicsError>) {
        let mut rec = Recorder::new(&self.model);
        let res = self.inverse(end, every, &mut |s| rec.record(s));
        (rec.into_table(), res)
    }

    /// What does work in the scene beyond the potential energy: `force 'motor'` for each force
    /// element that is not conservative and `driver 'crank'` for each driver, in order. Empty for
    /// a conservative model.
    pub fn nonconservative_elements(&self) -> Vec<String> {
        let forces = self.model.kind().nonconservative_force_names();
        let forces = forces.into_iter().map(|n| format!("force '{n}'"));
        let drivers = self.drivers().into_iter().map(|d| format!("driver '{d}'"));
        forces.chain(drivers).collect()
    }

    /// The names of the scene's drivers, in the order of their `<driver>.effort` columns.
    pub fn drivers(&self) -> Vec<String> {
        self.model.kind().driver_names()
    }
}
