//! The motion linearized in minimal coordinates: [`Scene::linearize`].
//!
//! About an operating point `(t₀, q₀, v₀, u₀)` (the static equilibrium, the scene's initial state
//! or a given state), coordinate partitioning chooses `dof` independent velocity coordinates
//! (or the caller names them). The state is `x = [δ_i, v_i]`: `δ_i` the independent
//! coordinates of the position `q = q₀ ⊕ δ` (the dependent ones solved from `C(q, t₀) = 0`), `v_i`
//! the independent velocities (the dependent ones from `C_q v + C_t = 0`). The scene's
//! formulation gives `v̇` at `(t₀, q, v, u)`, so `ẋ = f(x, u) = [δ̇_i, v̇_i]` (`δ̇` from
//! [`MultibodySystem::chart_rates`]) and any output column `y = g(x, u)` are exact functions of
//! `(x, u)`, and
//!
//! ```text
//! δẋ = A δx + B δu,    δy = C δx + D δu,    A = ∂f/∂x, B = ∂f/∂u, C = ∂g/∂x, D = ∂g/∂u
//! ```
//!
//! at `(x₀, u₀)`, by central differences with one Richardson extrapolation (error `O(h⁴)`, steps
//! `10⁻³` of each variable's scale: `docs/statics.md`, "Linearization"). At an equilibrium
//! `f(x₀, u₀) = 0`; elsewhere [`Linearization::drift`] holds it (the model is affine there).

use crate::equilibrium::EquilibriumError;
use crate::output::Rows;
use crate::scene::unknown_name;
use crate::Scene;
use dalembert_integrators::Sample;
use dalembert_system::inputs::with_inputs;
use dalembert_system::{
    ConstraintSet, ConstraintValues, Formulation, KinematicOptions, MultibodySystem, Partition, VelocityTransform,
};
use nalgebra::DMatrix;
use thiserror::Error;

/// Where a scene is linearized.
#[derive(Debug, Clone, PartialEq, Default)]
pub enum About {
    /// The static equilibrium ([`Scene::equilibrium`]) at time 0, inputs at 0.
    #[default]
    Equilibrium,
    /// The scene's initial state at time 0, inputs at 0.
    Initial,
    /// A given state: time, positions and velocities in the model's coordinates (assembled to
    /// the constraints first), and input values by name (the others 0).
    State {
        /// Time.
        t: f64,
        /// Positions.
        q: Vec<f64>,
        /// Velocities.
        qd: Vec<f64>,
        /// Input values by name.
        inputs: Vec<(String, f64)>,
    },
}

/// What to linearize: inputs, outputs, states and the operating point.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct LinearizeOptions {
    /// Named inputs of the scene (`{ input = "NAME" }`): the columns of `B` and `D`.
    pub inputs: Vec<String>,
    /// Output columns (the CSV's names): the rows of `C` and `D`.
    pub outputs: Vec<String>,
    /// The independent coordinates, by their position-state names (`rod.angle`, `slider.x`,
    /// `top.rx'`); empty: the scene's `[simulation] independent`, or coordinate partitioning's
    /// choice at the operating point.
    pub states: Vec<String>,
    /// The operating point.
    pub about: About,
}

/// A linear model `δẋ = A δx + B δu`, `δy = C δx + D δu` about an operating point.
#[derive(Debug, Clone, PartialEq)]
pub struct Linearization {
    /// `∂f/∂x` (`2 dof × 2 dof`).
    pub a: DMatrix<f64>,
    /// `∂f/∂u` (`2 dof × inputs`).
    pub b: DMatrix<f64>,
    /// `∂g/∂x` (`outputs × 2 dof`).
    pub c: DMatrix<f64>,
    /// `∂g/∂u` (`outputs × inputs`).
    pub d: DMatrix<f64>,
    /// `f(x₀, u₀)`: zero at an equilibrium (to its tolerance), the state's rate elsewhere.
    pub drift: Vec<f64>,
    /// The outputs at the operating point, `g(x₀, u₀)`.
    pub outputs_at: Vec<f64>,
    /// The state names: the position states (`rod.angle`; a spatial body's rotation from the
    /// operating point about its own axes `top.rx'`, …) and then the velocity states (`rod.omega`,
    /// `top.wx'`, …).
    pub states: Vec<String>,
    /// The input names (columns of `B`, `D`).
    pub inputs: Vec<String>,
    /// The output names (rows of `C`, `D`).
    pub outputs: Vec<String>,
    /// The operating point: time, …
    pub t: f64,
    /// … positions (assembled) …
    pub q: Vec<f64>,
    /// … and velocities.
    pub qd: Vec<f64>,
}

/// Why a scene could not be linearized (one line naming the cause).
#[derive(Debug, Error, Clone, PartialEq)]
pub enum LinearizationError {
    /// The equilibrium to linearize about was not found.
    #[error(transparent)]
    Equilibrium(#[from] EquilibriumError),
    /// A request the scene cannot meet: an unknown input, column or state, a state of the wrong
    /// size.
    #[error("linearize: {0}")]
    Request(String),
    /// The model cannot be linearized there (a singular position, a failed evaluation).
    #[error("linearize: {0}")]
    Model(String),
}

/// An operating point: time, positions, velocities and every input's value.
type OperatingPoint = (f64, Vec<f64>, Vec<f64>, Vec<f64>);

/// The outcome of one evaluation of `f` and `g`.
type Evaluated = Result<(), LinearizationError>;

/// `f` and `g` with one variable moved by the given amount.
type Probe<'p, 'a> = dyn FnMut(&mut Reduced<'a>, f64, &mut [f64], &mut [f64]) -> Evaluated + 'p;

/// Relative step of the central differences (of each variable's scale).
const STEP: f64 = 1e-3;
/// The position solve converges below this share of the length scale.
const POSITION_TOLERANCE: f64 = 1e-14;
/// Condition estimate of `C_qd` past which the chosen states do not determine the others.
const CONDITION_LIMIT: f64 = 1e12;

impl Scene {
    /// The motion linearized about `options.about` in minimal coordinates (see the module
    /// documentation), with the scene's formulation.
    pub fn linearize(&self, options: &LinearizeOptions) -> Result<Linearization, LinearizationError> {
        let request = LinearizationError::Request;
        if let Some(f) = self.model.system().frictions().first() {
            return Err(LinearizationError::Model(format!(
                "{} '{}' has Coulomb friction, which has no linearization (stick and slip are not smooth)",
                f.element, f.name
            )));
        }
        let input_of = options
            .inputs
            .iter()
            .map(|name| self.input_index(name))
            .collect::<Result<Vec<_>, _>>()?;
        let rows = Rows::new(&self.model);
        let output_of = options
            .outputs
            .iter()
            .map(|name| {
                rows.names().iter().position(|c| c == name).ok_or_else(|| {
                    let names: Vec<&str> = rows.names().iter().map(String::as_str).collect();
                    request(unknown_name("output column", name, &names))
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        let (t, q, qd, u) = self.operating_point(&options.about)?;
        // Limits: the linearization holds where every one is free (an impact has none).
        if let Some((l, s)) = dalembert_system::limit::limit_reached(self.model.system().as_ref(), t, &q) {
            return Err(LinearizationError::Model(format!(
                "{} '{}' is at or beyond its limits [{}, {}] at the operating point (its value {s}): an impact has no linearization; take a point inside them",
                l.element, l.name, l.lower, l.upper
            )));
        }
        let (position_names, velocity_names) = state_names(self.model.as_system());
        let system = self.model.as_system();
        let sys = system.constraints();
        let mut values = sys.values();
        with_inputs(&u, || sys.evaluate(t, &q, &qd, &mut values));
        // Joint values as states (`shoulder.q`, …): a spatial tree moved by its joints.
        let joint_states = self.joint_states(&options.states, &rows)?;
        let named_states: &[String] = if joint_states.is_some() { &[] } else { &options.states };
        let partition = self.partition(sys, &values, named_states, &position_names)?;
        if let Some(js) = &joint_states {
            if js.names.len() != partition.dof() {
                return Err(request(format!(
                    "{} joint values named where the model has {} degree(s) of freedom here (name every joint of a tree whose base is fixed)",
                    js.names.len(),
                    partition.dof()
                )));
            }
        }
        let mut transform = VelocityTransform::new(&partition, sys);
        if !transform.refactor(&values) || transform.condition > CONDITION_LIMIT {
            let named: Vec<&str> = partition
                .independent
                .iter()
                .map(|&k| position_names[k].as_str())
                .collect();
            return Err(request(format!(
                "the states {} do not determine the other coordinates at this position (the Jacobian of the others is singular); name others, or leave the choice to coordinate partitioning",
                named.join(", ")
            )));
        }
        // Free limits exert nothing near the point: the smooth formulation.
        let formulation = self
            .simulation()
            .formulation_without_switching()
            .map_err(|e| LinearizationError::Model(e.to_string()))?;
        let mut reduced = Reduced::new(
            self,
            formulation,
            partition,
            transform,
            (t, &q),
            u.clone(),
            input_of,
            rows,
            output_of,
        );
        let dof = reduced.partition.independent.len();
        let (nx, nu, ny) = (2 * dof, options.inputs.len(), options.outputs.len());
        let mut x0 = vec![0.0; nx];
        match &joint_states {
            Some(js) => {
                // The joints' values and rates at the operating point, from its output row.
                let row = reduced.row_at(&q, &qd)?;
                for (j, (&value, &rate)) in js.values.iter().zip(&js.rates).enumerate() {
                    x0[j] = row[value];
                    x0[dof + j] = row[rate];
                }
                let mut js = js.clone();
                js.at = x0[..dof].to_vec();
                reduced.joints = Some(js);
            }
            None => {
                for (j, &k) in reduced.partition.independent.iter().enumerate() {
                    x0[dof + j] = qd[k];
                }
            }
        }
        let u0: Vec<f64> = reduced.input_of.iter().map(|&k| u[k]).collect();
        let (mut drift, mut outputs_at) = (vec![0.0; nx], vec![0.0; ny]);
        reduced.eval(&x0, &u0, &mut drift, &mut outputs_at)?;
        // Steps: 10⁻³ rad for a rotation, 10⁻³ of the model's size for a translation, 10⁻³ of a
        // velocity's or an input's value (at least 10⁻³ of its unit).
        let size = length_scale(&q);
        let mut a = DMatrix::zeros(nx, nx);
        let mut b = DMatrix::zeros(nx, nu);
        let mut c = DMatrix::zeros(ny, nx);
        let mut d = DMatrix::zeros(ny, nu);
        let (mut df, mut dy) = (vec![0.0; nx], vec![0.0; ny]);
        for k in 0..nx + nu {
            let (mut x, mut uu) = (x0.clone(), u0.clone());
            let step = if k < dof && reduced.joints.is_some() {
                STEP // rad, or m: a joint value
            } else if k < dof {
                let name = &position_names[reduced.partition.independent[k]];
                STEP * if is_rotation(name) { 1.0 } else { size }
            } else if k < nx {
                STEP * (1.0 + x0[k].abs())
            } else {
                STEP * (1.0 + u0[k - nx].abs())
            };
            reduced.derivative(
                &mut |r: &mut Reduced, s: f64, f: &mut [f64], y: &mut [f64]| {
                    if k < nx {
                        x[k] = x0[k] + s;
                    } else {
                        uu[k - nx] = u0[k - nx] + s;
                    }
                    r.eval(&x, &uu, f, y)
                },
                step,
                (&mut df, &mut dy),
            )?;
            let (fcol, ycol) = if k < nx {
                (a.column_mut(k), c.column_mut(k))
            } else {
                (b.column_mut(k - nx), d.column_mut(k - nx))
            };
            fcol.into_iter().zip(&df).for_each(|(o, v)| *o = *v);
            ycol.into_iter().zip(&dy).for_each(|(o, v)| *o = *v);
        }
        let independent = &reduced.partition.independent;
        let states = match &reduced.joints {
            Some(js) => (js.names.iter().map(|n| format!("{n}.q")))
                .chain(js.names.iter().map(|n| format!("{n}.qd")))
                .collect(),
            None => (independent.iter().map(|&k| position_names[k].clone()))
                .chain(independent.iter().map(|&k| velocity_names[k].clone()))
                .collect(),
        };
        Ok(Linearization {
            a,
            b,
            c,
            d,
            drift,
            outputs_at,
            states,
            inputs: options.inputs.clone(),
            outputs: options.outputs.clone(),
            t,
            q,
            qd,
        })
    }

    /// The index of input `name` among the scene's inputs.
    fn input_index(&self, name: &str) -> Result<usize, LinearizationError> {
        self.inputs.iter().position(|i| i == name).ok_or_else(|| {
            LinearizationError::Request(if self.inputs.is_empty() {
                format!(
                    "unknown input '{name}': the scene has no inputs (a function {{ input = \"NAME\" }} declares one)"
                )
            } else {
                let names: Vec<&str> = self.inputs.iter().map(String::as_str).collect();
                unknown_name("input", name, &names)
            })
        })
    }

    /// Joint-value states: every name in `states` a `JOINT.q` column of a spatial model (then
    /// the joints, with their value and rate columns in `rows`); `None` otherwise.
    fn joint_states(&self, states: &[String], rows: &Rows) -> Result<Option<JointStates>, LinearizationError> {
        let names = rows.names();
        let column = |n: &str| names.iter().position(|c| c == n);
        let joint_values: Vec<&str> = states.iter().filter_map(|s| s.strip_suffix(".q")).collect();
        if states.is_empty() || self.model.spatial().is_none() || joint_values.len() != states.len() {
            return Ok(None);
        }
        let mut js = JointStates::default();
        for joint in joint_values {
            let (Some(value), Some(rate), Some(acceleration)) = (
                column(&format!("{joint}.q")),
                column(&format!("{joint}.qd")),
                column(&format!("{joint}.qdd")),
            ) else {
                return Ok(None);
            };
            js.names.push(joint.to_string());
            js.values.push(value);
            js.rates.push(rate);
            js.accelerations.push(acceleration);
        }
        Ok(Some(js))
    }

    /// The operating point `(t, q, v, inputs)`, assembled to the constraints.
    fn operating_point(&self, about: &About) -> Result<OperatingPoint, LinearizationError> {
        let n_v = self.model.num_velocities();
        let mut u = vec![0.0; self.inputs.len()];
        let (t, mut q, mut qd) = match about {
            About::Equilibrium => (0.0, self.equilibrium()?.q, vec![0.0; n_v]),
            About::Initial => (0.0, self.q.clone(), self.qd.clone()),
            About::State { t, q, qd, inputs } => {
                let n_q = self.model.num_positions();
                if q.len() != n_q || qd.len() != n_v {
                    return Err(LinearizationError::Request(format!(
                        "the model has {n_q} positions and {n_v} velocities; {} and {} were given",
                        q.len(),
                        qd.len()
                    )));
                }
                if let Some(x) = q.iter().chain(qd).chain(std::iter::once(t)).find(|x| !x.is_finite()) {
                    return Err(LinearizationError::Request(format!(
                        "the state holds {x}, not a finite value"
                    )));
                }
                for (name, value) in inputs {
                    if !value.is_finite() {
                        return Err(LinearizationError::Request(format!(
                            "input '{name}': {value} is not a finite value"
                        )));
                    }
                    u[self.input_index(name)?] = *value;
                }
                (*t, q.clone(), qd.clone())
            }
        };
        let sys = self.model.as_system().constraints();
        let opts = KinematicOptions::default();
        with_inputs(&u, || -> Result<(), dalembert_system::ConstraintError> {
            sys.solve_positions(t, &mut q, &opts)?;
            sys.solve_velocities_weighted(t, &q, &mut qd, None, &opts)
        })
        .map_err(|e| LinearizationError::Model(format!("the operating point cannot be assembled: {e}")))?;
        Ok((t, q, qd, u))
    }

    /// The partition at the operating point: the named states, the scene's `independent`, or
    /// coordinate partitioning's choice; a singular position is refused.
    fn partition(
        &self,
        sys: &dyn ConstraintSet,
        values: &ConstraintValues,
        states: &[String],
        position_names: &[String],
    ) -> Result<Partition, LinearizationError> {
        let chosen = Partition::choose(sys, values, 1e-9);
        let structure = self.structure().map_err(|e| LinearizationError::Model(e.to_string()))?;
        if chosen.rows.len() < structure.rank {
            return Err(LinearizationError::Model(format!(
                "the operating point is a singular position: the constraint Jacobian has rank {} there where the mechanism has {} (no minimal coordinates describe the motion there; linearize near it)",
                chosen.rows.len(),
                structure.rank
            )));
        }
        let named = if states.is_empty() {
            self.settings.independent.clone()
        } else {
            let names: Vec<&str> = position_names.iter().map(String::as_str).collect();
            let indices = states
                .iter()
                .map(|s| {
                    names
                        .iter()
                        .position(|n| n == s)
                        .ok_or_else(|| LinearizationError::Request(unknown_name("state", s, &names)))
                })
                .collect::<Result<Vec<_>, _>>()?;
            Some(indices)
        };
        let Some(mut independent) = named else {
            return Ok(chosen);
        };
        independent.sort_unstable();
        independent.dedup();
        if independent.len() != chosen.dof() {
            return Err(LinearizationError::Request(format!(
                "{} states named where the model has {} degree(s) of freedom here",
                independent.len(),
                chosen.dof()
            )));
        }
        let dependent = (0..sys.num_coordinates())
            .filter(|c| independent.binary_search(c).is_err())
            .collect();
        Ok(Partition {
            dependent,
            independent,
            rows: chosen.rows,
        })
    }
}

/// The model's size for translation steps: the largest coordinate at `q` (1 where all are 0).
fn length_scale(q: &[f64]) -> f64 {
    let largest = q.iter().fold(0.0f64, |a, x| a.max(x.abs()));
    if largest > 0.0 {
        largest
    } else {
        1.0
    }
}

/// A position state that is a rotation (its step is in radians).
fn is_rotation(name: &str) -> bool {
    name.ends_with(".angle") || name.ends_with('\'')
}

/// The names of the position and velocity states of each velocity coordinate: a planar body's
/// `x, y, angle` and `vx, vy, omega`; a spatial body's `x, y, z, rx', ry', rz'` (rotation from the
/// operating point about its own axes) and `vx, vy, vz, wx', wy', wz'`.
fn state_names(system: &dyn MultibodySystem) -> (Vec<String>, Vec<String>) {
    let mut positions = Vec::new();
    let mut velocities = Vec::new();
    for b in system.layout().bodies() {
        for &label in b.v_labels {
            let (p, v) = match label {
                "x" | "vx" => ("x".to_string(), "vx".to_string()),
                "y" | "vy" => ("y".to_string(), "vy".to_string()),
                "vz" => ("z".to_string(), "vz".to_string()),
                "angle" => ("angle".to_string(), "omega".to_string()),
                other => match other.strip_prefix('w') {
                    Some(axis) => (format!("r{axis}"), other.to_string()),
                    None => (other.to_string(), format!("{other}_rate")),
                },
            };
            positions.push(format!("{}.{p}", b.name));
            velocities.push(format!("{}.{v}", b.name));
        }
    }
    (positions, velocities)
}

/// States that are joint values and rates: the joints' names and their `.q` and `.qd` columns.
#[derive(Debug, Clone, Default)]
struct JointStates {
    names: Vec<String>,
    values: Vec<usize>,
    rates: Vec<usize>,
    accelerations: Vec<usize>,
    /// The joints' values at the operating point (the moves are from there).
    at: Vec<f64>,
}

/// The reduced dynamics `f(x, u)` and outputs `g(x, u)` at a fixed time and partition.
struct Reduced<'a> {
    system: &'a dyn MultibodySystem,
    /// The spatial model, for joint-value states.
    spatial: Option<&'a dalembert_spatial::Model>,
    formulation: Box<dyn Formulation>,
    partition: Partition,
    transform: VelocityTransform,
    values: ConstraintValues,
    t: f64,
    q0: Vec<f64>,
    /// Every input's value (those linearized in are overwritten per evaluation).
    u: Vec<f64>,
    input_of: Vec<usize>,
    rows: Rows,
    row: Vec<f64>,
    output_of: Vec<usize>,
    delta: Vec<f64>,
    q: Vec<f64>,
    v: Vec<f64>,
    rates: Vec<f64>,
    qdd: Vec<f64>,
    lambda: Vec<f64>,
    c: Vec<f64>,
    cdot: Vec<f64>,
    product: Vec<f64>,
    y: Vec<f64>,
    size: f64,
    /// Joint values and rates as the state (a spatial tree), instead of the partition's.
    joints: Option<JointStates>,
}

impl<'a> Reduced<'a> {
    #[allow(clippy::too_many_arguments)]
    fn new(
        scene: &'a Scene,
        formulation: Box<dyn Formulation>,
        partition: Partition,
        transform: VelocityTransform,
        (t, q0): (f64, &[f64]),
        u: Vec<f64>,
        input_of: Vec<usize>,
        rows: Rows,
        output_of: Vec<usize>,
    ) -> Self {
        let system = scene.model.as_system();
        let (n_q, n_v, m) = (q0.len(), system.layout().n_v(), system.num_equations());
        let r = partition.rows.len();
        Reduced {
            system,
            spatial: scene.model.spatial(),
            formulation,
            partition,
            transform,
            values: system.constraints().values(),
            t,
            q0: q0.to_vec(),
            u,
            input_of,
            rows,
            row: Vec::new(),
            output_of,
            delta: vec![0.0; n_v],
            q: vec![0.0; n_q],
            v: vec![0.0; n_v],
            rates: vec![0.0; n_v],
            qdd: vec![0.0; n_v],
            lambda: vec![0.0; m],
            c: vec![0.0; m],
            cdot: vec![0.0; m],
            product: vec![0.0; m],
            y: vec![0.0; r],
            size: 1.0 + q0.iter().fold(0.0f64, |a, x| a.max(x.abs())),
            joints: None,
        }
    }

    /// The output row at `(q, v)` (accelerations at the current inputs).
    fn row_at(&mut self, q: &[f64], v: &[f64]) -> Result<Vec<f64>, LinearizationError> {
        self.q.copy_from_slice(q);
        self.v.copy_from_slice(v);
        self.sample_row()?;
        Ok(self.row.clone())
    }

    /// The output row at the state in `self.q`, `self.v` into `self.row`.
    fn sample_row(&mut self) -> Result<(), LinearizationError> {
        let t = self.t;
        let Reduced {
            formulation,
            q,
            v,
            qdd,
            lambda,
            c,
            cdot,
            u,
            ..
        } = self;
        let energy = with_inputs(u, || -> Result<f64, LinearizationError> {
            formulation
                .accelerations(t, q, v, None, qdd, lambda)
                .map_err(|e| LinearizationError::Model(e.to_string()))?;
            formulation.residuals(t, q, v, c, cdot);
            Ok(formulation.energy(t, q, v).total())
        })?;
        let largest = |x: &[f64]| x.iter().fold(0.0f64, |a, v| a.max(v.abs()));
        self.row.clear();
        self.rows.push(
            &Sample {
                t,
                q: &self.q,
                qd: &self.v,
                qdd: &self.qdd,
                lambda: &self.lambda,
                friction: &[],
                limit: &[],
                impact_loss: 0.0,
                work: f64::NAN,
                constraint_violation: largest(&self.c),
                velocity_violation: largest(&self.cdot),
                energy,
            },
            &mut self.row,
        );
        Ok(())
    }

    /// `f(x, u)` and `g(x, u)` with joint values and rates as the state: the tree turned from the
    /// operating point by each joint's change of value, its rates set from rest
    /// ([`dalembert_spatial::Model::move_joints`], whose moves are relative), `f` read from the
    /// joints' rate and acceleration columns.
    fn eval_joints(&mut self, x: &[f64], f: &mut [f64], y: &mut [f64]) -> Result<(), LinearizationError> {
        let Some(js) = self.joints.clone() else {
            return Ok(());
        };
        let dof = js.names.len();
        let model = self
            .spatial
            .ok_or_else(|| LinearizationError::Model("joint values need a spatial model".into()))?;
        let moves: Vec<dalembert_spatial::joint_values::JointMove> = (js.names.iter().enumerate())
            .map(|(j, n)| dalembert_spatial::joint_values::JointMove {
                joint: n.clone(),
                value: x[j] - js.at[j],
                rate: x[dof + j],
            })
            .collect();
        self.q.copy_from_slice(&self.q0);
        self.v.fill(0.0);
        model
            .move_joints(&mut self.q, &mut self.v, &moves)
            .map_err(|e| LinearizationError::Model(e.to_string()))?;
        self.sample_row()?;
        for (j, (&rate, &acceleration)) in js.rates.iter().zip(&js.accelerations).enumerate() {
            f[j] = self.row[rate];
            f[dof + j] = self.row[acceleration];
        }
        for (o, &k) in y.iter_mut().zip(&self.output_of) {
            *o = self.row[k];
        }
        Ok(())
    }

    /// `f(x, u)` into `f` and `g(x, u)` into `y`.
    fn eval(&mut self, x: &[f64], u: &[f64], f: &mut [f64], y: &mut [f64]) -> Result<(), LinearizationError> {
        if self.joints.is_some() {
            for (j, &k) in self.input_of.iter().enumerate() {
                self.u[k] = u[j];
            }
            return self.eval_joints(x, f, y);
        }
        let Reduced {
            system,
            partition,
            transform,
            values,
            t,
            ..
        } = self;
        let (system, t) = (*system, *t);
        let sys = system.constraints();
        let dof = partition.independent.len();
        for (j, &k) in self.input_of.iter().enumerate() {
            self.u[k] = u[j];
        }
        let inputs = &self.u;
        // Positions: δ_i given, δ_d by Newton's method on C(q₀ ⊕ δ, t) = 0 over the independent
        // equations (the Jacobian in velocity coordinates: quadratic convergence up to a factor
        // 1 + O(|δ|) for a rotation).
        self.delta.fill(0.0);
        for (j, &k) in partition.independent.iter().enumerate() {
            self.delta[k] = x[j];
        }
        let tolerance = POSITION_TOLERANCE * self.size;
        let mut previous = f64::INFINITY;
        for iteration in 0.. {
            self.q.copy_from_slice(&self.q0);
            system.integrate_positions(&mut self.q, &self.delta, 1.0);
            system.normalize(&mut self.q);
            with_inputs(inputs, || sys.evaluate(t, &self.q, &self.v, values));
            let residual = partition.rows.iter().fold(0.0f64, |a, &r| a.max(values.c[r].abs()));
            // Done at the tolerance, or where the residual stops falling near round-off.
            if residual <= tolerance || (residual >= 0.5 * previous && residual <= 1e3 * tolerance) {
                break;
            }
            if iteration == 50 || !residual.is_finite() || !transform.refactor(values) {
                return Err(LinearizationError::Model(format!(
                    "the position {:.3e} away from the operating point cannot be assembled (constraint violation {residual:.3e})",
                    x[..dof].iter().fold(0.0f64, |a, v| a.max(v.abs()))
                )));
            }
            previous = residual;
            for (yi, &r) in self.y.iter_mut().zip(&partition.rows) {
                *yi = -values.c[r];
            }
            transform.solve_dependent(&mut self.y);
            for (k, &d) in partition.dependent.iter().enumerate() {
                self.delta[d] += self.y[k];
            }
        }
        // Velocities: v_i given, v_d from C_q v + C_t = 0 at this position.
        if !transform.refactor(values) {
            return Err(LinearizationError::Model(
                "the constraint Jacobian of the dependent coordinates is singular near the operating point".into(),
            ));
        }
        self.v.fill(0.0);
        for (j, &k) in partition.independent.iter().enumerate() {
            self.v[k] = x[dof + j];
        }
        self.product.fill(0.0);
        for (&(row, col), &value) in sys.pattern().entries().iter().zip(&values.jacobian) {
            self.product[row] += value * self.v[col];
        }
        for (yi, &r) in self.y.iter_mut().zip(&partition.rows) {
            *yi = -(values.c_t[r] + self.product[r]);
        }
        transform.solve_dependent(&mut self.y);
        for (k, &d) in partition.dependent.iter().enumerate() {
            self.v[d] = self.y[k];
        }
        // Accelerations from the scene's formulation (and the output row), and the chart's rates.
        self.sample_row()?;
        system.chart_rates(&self.delta, &self.v, &mut self.rates);
        for (j, &k) in self.partition.independent.iter().enumerate() {
            f[j] = self.rates[k];
            f[dof + j] = self.qdd[k];
        }
        for (o, &k) in y.iter_mut().zip(&self.output_of) {
            *o = self.row[k];
        }
        Ok(())
    }

    /// The derivative of `(f, g)` along one variable, `at(s)` evaluating them with the variable
    /// moved by `s`: central differences at `h` and `h/2`, extrapolated (`(4 D(h/2) − D(h)) / 3`).
    fn derivative(
        &mut self,
        at: &mut Probe<'_, 'a>,
        h: f64,
        (df, dy): (&mut [f64], &mut [f64]),
    ) -> Result<(), LinearizationError> {
        let (nx, ny) = (df.len(), dy.len());
        let mut f = [vec![0.0; nx], vec![0.0; nx], vec![0.0; nx], vec![0.0; nx]];
        let mut y = [vec![0.0; ny], vec![0.0; ny], vec![0.0; ny], vec![0.0; ny]];
        for (k, s) in [h, -h, 0.5 * h, -0.5 * h].into_iter().enumerate() {
            at(self, s, &mut f[k], &mut y[k])?;
        }
        let extrapolate = |v: &[Vec<f64>], out: &mut [f64]| {
            for (i, o) in out.iter_mut().enumerate() {
                let wide = (v[0][i] - v[1][i]) / (2.0 * h);
                let narrow = (v[2][i] - v[3][i]) / h;
                *o = (4.0 * narrow - wide) / 3.0;
            }
        };
        extrapolate(&f, df);
        extrapolate(&y, dy);
        Ok(())
    }
}
