//! Sensitivities of a run's outputs to scene parameters: `∂(column)/∂p` at every output time, for
//! any value a scene sets by path ([`Scene::with_values`]: masses, inertias, stiffnesses,
//! damping, lengths, points).
//!
//! The run carries `S = ∂y/∂p` along with its state ([`dalembert_integrators::Perturbed`]): each
//! of its steps is taken again, by the same method with the same size, from `y ± δ S` on the scene
//! with `p ± δ`, and `S ← (y₊ − y₋) / 2δ`. The sensitivities are those of the numerical solution
//! the run computes (its method and steps differentiated), recentred on the run at every step; an output column's derivative is `(column₊ − column₋) / 2δ` between the two models'
//! samples at the output time. The equations, the choice of `δ` and the measured accuracy are in
//! `docs/sensitivities.md`.
//!
//! ```
//! # fn main() -> Result<(), Box<dyn std::error::Error>> {
//! use dalembert::{Scene, SensitivityRequest};
//! let scene = Scene::from_path("scenes/pendulum.toml")?
//!     .with_values(&[("simulation.end", 0.5.into())])?;
//! let request = SensitivityRequest::new(&["bodies.rod.mass"], &["rod.angle"]);
//! let run = scene.sensitivities(&request, &Default::default())?;
//! // A pendulum's motion does not depend on its mass: ∂θ/∂m = 0 at every output time.
//! let d = run.sensitivity("rod.angle", "bodies.rod.mass").unwrap();
//! assert!(d.iter().all(|x| x.abs() < 1e-7));
//! # Ok(()) }
//! ```

use crate::output::{Recorder, Rows, Table};
use crate::scene::{Scene, SceneError, SceneValue};
use crate::simulation::{Coordinates, SimulationError};
use dalembert_integrators::{integrate_sensitivities, Perturbed, PerturbedSide, Sample, Statistics};
use dalembert_system::Frictional;
use std::sync::atomic::AtomicBool;
use thiserror::Error;

/// The default relative change of a parameter: `δ = 1e-4 |p|` (`1e-4` in the parameter's units
/// when `p = 0`). The central differences' truncation is about `δ²` relative (1e-8); a smaller
/// change lets the round-off of every step, `1e-16 |y| / (δ |S|)`, accumulate over the run
/// instead (measured in `docs/sensitivities.md`).
pub const RELATIVE_CHANGE: f64 = 1e-4;

/// What sensitivities to compute.
#[derive(Debug, Clone, PartialEq)]
pub struct SensitivityRequest {
    /// Scene paths of the parameters (`bodies.upper.mass`, `forces.spring.stiffness`).
    pub parameters: Vec<String>,
    /// The output columns differentiated (`lower.x`, `pin.fy`); empty: every column but `t`.
    pub of: Vec<String>,
    /// `δ = relative_change · |p|` (or `relative_change` when `p = 0`).
    pub relative_change: f64,
}

impl SensitivityRequest {
    /// The sensitivities of the columns `of` (empty: all but `t`) to `parameters`, with the
    /// default change.
    pub fn new(parameters: &[&str], of: &[&str]) -> Self {
        SensitivityRequest {
            parameters: parameters.iter().map(|s| s.to_string()).collect(),
            of: of.iter().map(|s| s.to_string()).collect(),
            relative_change: RELATIVE_CHANGE,
        }
    }
}

/// Why sensitivities cannot be set up (one line naming the parameter or column).
#[derive(Debug, Error)]
pub enum SensitivityError {
    /// The request itself: an unknown column, a parameter that is not a number of the scene, a
    /// change that is not positive, a setting the sensitivities cannot follow.
    #[error("{0}")]
    Request(String),
    /// The scene with a parameter changed cannot be built.
    #[error(transparent)]
    Scene(#[from] SceneError),
    /// The scene with a parameter changed cannot start (assembly or formulation).
    #[error("with '{parameter}' changed: {error}")]
    Changed {
        /// The parameter.
        parameter: String,
        /// What failed.
        error: SimulationError,
    },
}

/// The derivatives of chosen output columns from the two samples of each parameter's models: the
/// columns `d(column)/d(parameter)`, parameter after parameter.
#[derive(Debug, Clone)]
pub struct SensitivityColumns {
    names: Vec<String>,
    /// Indices of the differentiated columns in a row of the scene's output.
    of: Vec<usize>,
    /// Per parameter, the rows of its `p + δ` and `p − δ` models.
    rows: Vec<[Rows; 2]>,
    plus: Vec<f64>,
    minus: Vec<f64>,
    values: Vec<f64>,
}

impl SensitivityColumns {
    /// The names `d(column)/d(parameter)`.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// Takes one sample of a perturbed model; returns the row of derivatives (every parameter)
    /// when this was the last sample of the output time.
    fn take(&mut self, s: &Sample<'_>, side: PerturbedSide) -> Option<&[f64]> {
        let rows = &mut self.rows[side.parameter][usize::from(!side.plus)];
        if side.plus {
            self.plus.clear();
            rows.push(s, &mut self.plus);
            return None;
        }
        self.minus.clear();
        rows.push(s, &mut self.minus);
        let n = self.of.len();
        let first = side.parameter * n;
        for (k, &c) in self.of.iter().enumerate() {
            self.values[first + k] = (self.plus[c] - self.minus[c]) / (2.0 * side.delta);
        }
        (side.parameter + 1 == self.rows.len()).then_some(&self.values[..])
    }
}

/// A run with sensitivities, kept in memory.
#[derive(Debug)]
pub struct SensitivityRecording {
    /// The run's rows (as [`Scene::record`]).
    pub table: Table,
    /// `t` and the columns `d(column)/d(parameter)`, one row per output time.
    pub sensitivities: Table,
    /// Statistics of the finished run, or why it stopped (every row before is kept).
    pub outcome: Result<Statistics, SimulationError>,
    /// The energy warning of a conservative model whose `T + V` drifted (as [`Scene::record`]).
    pub warning: Option<String>,
}

impl SensitivityRecording {
    /// `∂column/∂parameter` at every output time, or `None` when it was not computed.
    pub fn sensitivity(&self, column: &str, parameter: &str) -> Option<Vec<f64>> {
        self.sensitivities.column(&column_name(column, parameter))
    }
}

/// The name of a sensitivity column.
pub fn column_name(column: &str, parameter: &str) -> String {
    format!("d({column})/d({parameter})")
}

/// The setup of a run with sensitivities: the perturbed scenes' formulations and states, and the
/// columns they give.
pub struct SensitivitySetup {
    perturbed: Vec<Perturbed>,
    /// The derivative columns.
    pub columns: SensitivityColumns,
}

impl Scene {
    /// The value of the number at `path` as the scene file writes it, or an error naming the path
    /// (not a number, or not written in the file: its default is the format's, not known here).
    pub fn number_at(&self, path: &str) -> Result<f64, SceneError> {
        self.check_path(path)?;
        let fail = |message: String| SceneError {
            file: self.origin.clone(),
            position: None,
            message,
        };
        match crate::scene::values::value_at(&self.source, path).map_err(&fail)? {
            Some(SceneValue::Number(x)) => Ok(x),
            Some(SceneValue::Integer(i)) => Ok(i as f64),
            Some(v) => Err(fail(format!(
                "'{path}' is {v}, not a number: a sensitivity needs a number"
            ))),
            None => Err(fail(format!(
                "'{path}' is not written in the scene: write its value there to take a sensitivity to it"
            ))),
        }
    }

    /// Sets up a run with the sensitivities `request` asks for: each parameter's scene with
    /// `p ± δ`, assembled, and its formulation.
    pub fn sensitivity_setup(&self, request: &SensitivityRequest) -> Result<SensitivitySetup, SensitivityError> {
        let bad = |m: String| Err(SensitivityError::Request(m));
        if self.settings.coordinates == Coordinates::Joint {
            return bad(
                "sensitivities follow a run in the model's own coordinates: run it with coordinates = \"absolute\""
                    .into(),
            );
        }
        if let Some(f) = self.model.system().frictions().first() {
            return bad(format!(
                "{} '{}' has Coulomb friction, whose stick and slip switch at events: a run with friction has no sensitivities yet",
                f.element, f.name
            ));
        }
        if !(request.relative_change.is_finite() && request.relative_change > 0.0 && request.relative_change < 0.1) {
            return bad(format!(
                "the relative change of a parameter must be in (0, 0.1), got {}",
                request.relative_change
            ));
        }
        if request.parameters.is_empty() {
            return bad("name at least one parameter (a scene path, e.g. bodies.upper.mass)".into());
        }
        let own = Rows::new(&self.model);
        let of: Vec<usize> = if request.of.is_empty() {
            (1..own.names().len()).collect()
        } else {
            let table = Table {
                columns: own.names().to_vec(),
                data: Vec::new(),
            };
            let mut of = Vec::new();
            for c in &request.of {
                match table.index(c) {
                    Some(k) => of.push(k),
                    None => return bad(table.unknown_column(c)),
                }
            }
            of
        };
        let (mut perturbed, mut rows, mut names) = (Vec::new(), Vec::new(), Vec::new());
        for (k, path) in request.parameters.iter().enumerate() {
            if request.parameters[..k].contains(path) {
                return bad(format!("'{path}' is named twice"));
            }
            if path.starts_with("simulation.") {
                return bad(format!("'{path}' is a run setting, not a value of the model: a sensitivity is taken to a model's value (a mass, a stiffness, a length)"));
            }
            let p = self.number_at(path)?;
            let delta = request.relative_change * if p == 0.0 { 1.0 } else { p.abs() };
            let changed = |sign: f64| -> Result<_, SensitivityError> {
                let mut scene = self.with_values(&[(path.as_str(), SceneValue::Number(p + sign * delta))])?;
                // The run's settings as given (overridden on the command line or in Python), not
                // as the file writes them.
                scene.settings = self.settings.clone();
                let fail = |error: SimulationError| SensitivityError::Changed {
                    parameter: path.clone(),
                    error,
                };
                let mut sim = scene.simulation();
                sim.assemble().map_err(fail)?;
                if sim.q.len() != self.q.len() || sim.qd.len() != self.qd.len() {
                    return Err(SensitivityError::Request(format!(
                        "'{path}' changes the model's coordinates: a sensitivity needs the same model"
                    )));
                }
                // Free limits exert nothing; the run itself stops where one is reached.
                let f = sim.formulation_without_switching().map_err(fail)?;
                let y = [sim.q.as_slice(), sim.qd.as_slice()].concat();
                Ok((f, y, Rows::new(&scene.model)))
            };
            let (plus, y_plus, rows_plus) = changed(1.0)?;
            let (minus, y_minus, rows_minus) = changed(-1.0)?;
            perturbed.push(Perturbed {
                name: path.clone(),
                plus,
                minus,
                y_plus,
                y_minus,
                delta,
            });
            rows.push([rows_plus, rows_minus]);
            names.extend(of.iter().map(|&c| column_name(&own.names()[c], path)));
        }
        let width = own.names().len();
        Ok(SensitivitySetup {
            perturbed,
            columns: SensitivityColumns {
                values: vec![0.0; names.len()],
                names,
                of,
                rows,
                plus: Vec::with_capacity(width),
                minus: Vec::with_capacity(width),
            },
        })
    }

    /// Runs the scene with `setup`'s sensitivities: `observer` gets every output sample of the run
    /// and the row of derivatives there (in the order of [`SensitivityColumns::names`]).
    pub fn run_sensitivities(
        &self,
        setup: SensitivitySetup,
        observer: &mut dyn FnMut(&Sample<'_>, &[f64]),
        cancel: &AtomicBool,
    ) -> Result<Statistics, SimulationError> {
        let SensitivitySetup { perturbed, mut columns } = setup;
        let sim = self.simulation();
        // With limits: the run holds while they are free, and stops where one is reached (a
        // sensitivity across an impact is not built).
        let mut f = if self.model.system().limits().is_empty() {
            sim.formulation()?
        } else {
            Box::new(Frictional::new(sim.formulation_without_switching()?)?.refusing_impacts())
        };
        // The run's own sample is kept until the derivatives of its time are complete (the
        // observer sees both together).
        let mut last: Vec<f64> = Vec::new();
        let mut q = Vec::new();
        let mut qd = Vec::new();
        let mut qdd = Vec::new();
        let mut lambda = Vec::new();
        let mut friction = Vec::new();
        let result = integrate_sensitivities(
            f.as_mut(),
            sim.start,
            sim.end,
            &sim.q,
            &sim.qd,
            &sim.integrator,
            perturbed,
            &mut |s, side| match side {
                None => {
                    last.clear();
                    last.extend_from_slice(&[s.t, s.constraint_violation, s.velocity_violation, s.energy]);
                    for (to, from) in [
                        (&mut q, s.q),
                        (&mut qd, s.qd),
                        (&mut qdd, s.qdd),
                        (&mut lambda, s.lambda),
                        (&mut friction, s.friction),
                    ] {
                        to.clear();
                        to.extend_from_slice(from);
                    }
                }
                Some(side) => {
                    if let Some(values) = columns.take(s, side) {
                        let sample = Sample {
                            t: last[0],
                            q: &q,
                            qd: &qd,
                            qdd: &qdd,
                            lambda: &lambda,
                            friction: &friction,
                            limit: &[],
                            impact_loss: 0.0,
                            work: f64::NAN,
                            constraint_violation: last[1],
                            velocity_violation: last[2],
                            energy: last[3],
                        };
                        observer(&sample, values);
                    }
                }
            },
            cancel,
        );
        Ok(result?)
    }

    /// Runs the scene with the sensitivities `request` asks for and keeps the rows in memory.
    pub fn sensitivities(
        &self,
        request: &SensitivityRequest,
        cancel: &AtomicBool,
    ) -> Result<SensitivityRecording, SensitivityError> {
        let setup = self.sensitivity_setup(request)?;
        let mut rec = Recorder::new(&self.model);
        let mut columns = vec!["t".to_string()];
        columns.extend(setup.columns.names().iter().cloned());
        let mut sensitivities = Table {
            columns,
            data: Vec::new(),
        };
        let outcome = self.run_sensitivities(
            setup,
            &mut |s, values| {
                rec.record(s);
                sensitivities.data.push(s.t);
                sensitivities.data.extend_from_slice(values);
            },
            cancel,
        );
        Ok(SensitivityRecording {
            table: rec.into_table(),
            sensitivities,
            warning: self.energy_warning_of(&outcome),
            outcome,
        })
    }
}
