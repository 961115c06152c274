//! The columns of a run's output, and a run kept in memory (the Python package, sweeps).
//!
//! [`Rows`] names the columns of a model's output and fills one row of numbers from a sample; the
//! CSV writer and the in-memory [`Table`] both use it, so a column means the same thing in a file,
//! a numpy array and a sweep.

use crate::mechanism::Mechanism;
use crate::system::ConstraintSet as _;
use dalembert_constraints::{ConstraintRole, Model, Reaction};
use dalembert_integrators::Sample;
use dalembert_spatial::frame::Frame;
use dalembert_system::ConstraintValues;

/// The output columns of one model and the scratch space to compute a row (allocation-free after
/// construction).
#[derive(Debug, Clone)]
pub struct Rows {
    names: Vec<String>,
    /// Index of the first reaction or effort column.
    first_reaction: usize,
    scratch: Scratch,
}

/// What a row is computed with, per kind of model.
#[derive(Debug, Clone)]
enum Scratch {
    Planar {
        roles: Vec<ConstraintRole>,
        values: ConstraintValues,
        reactions: Vec<Reaction>,
    },
    Spatial {
        reactions: Vec<dalembert_spatial::Reaction>,
        drivers: usize,
    },
}

/// The columns of a spatial body: centre of mass, Euler parameters, centre-of-mass velocity and
/// angular velocity (global components).
pub const SPATIAL_BODY_COLUMNS: [&str; 13] = [
    "x", "y", "z", "e0", "e1", "e2", "e3", "vx", "vy", "vz", "wx", "wy", "wz",
];

/// The columns of a spatial joint: force and moment (about the joint's point) that its second body
/// exerts on its first, global components.
pub const SPATIAL_JOINT_COLUMNS: [&str; 6] = ["fx", "fy", "fz", "mx", "my", "mz"];

impl Rows {
    /// The columns of `model` (see the module documentation of [`crate::output`]).
    pub fn new(model: &Mechanism) -> Self {
        match model {
            Mechanism::Planar(m) => Rows::planar(m),
            Mechanism::Spatial(m) => Rows::spatial(m),
        }
    }

    fn planar(model: &Model) -> Self {
        let mut names = vec!["t".to_string()];
        for b in model.bodies() {
            for c in ["x", "y", "angle", "vx", "vy", "omega"] {
                names.push(format!("{}.{c}", b.name));
            }
        }
        let first_reaction = names.len();
        let sys = model.constraints();
        let roles: Vec<ConstraintRole> = sys.constraints().iter().map(|c| c.role()).collect();
        for (c, role) in sys.constraints().iter().zip(&roles) {
            match role {
                ConstraintRole::Joint { carries_torque } => {
                    names.push(format!("{}.fx", c.name()));
                    names.push(format!("{}.fy", c.name()));
                    if *carries_torque {
                        names.push(format!("{}.torque", c.name()));
                    }
                }
                ConstraintRole::Driver => names.push(format!("{}.effort", c.name())),
            }
        }
        names.extend(TRAILING_COLUMNS.map(String::from));
        Rows {
            names,
            first_reaction,
            scratch: Scratch::Planar {
                values: sys.values(),
                reactions: vec![Reaction::default(); roles.len()],
                roles,
            },
        }
    }

    fn spatial(model: &dalembert_spatial::Model) -> Self {
        let mut names = vec!["t".to_string()];
        for b in model.bodies() {
            names.extend(SPATIAL_BODY_COLUMNS.iter().map(|c| format!("{}.{c}", b.name)));
        }
        let first_reaction = names.len();
        for j in model.joint_names() {
            names.extend(SPATIAL_JOINT_COLUMNS.iter().map(|c| format!("{j}.{c}")));
        }
        let drivers: Vec<String> = model.driver_names().map(|d| format!("{d}.effort")).collect();
        let n_drivers = drivers.len();
        names.extend(drivers);
        names.extend(TRAILING_COLUMNS.map(String::from));
        Rows {
            names,
            first_reaction,
            scratch: Scratch::Spatial {
                reactions: vec![
                    dalembert_spatial::Reaction {
                        force: Default::default(),
                        moment: Default::default(),
                        point: Default::default(),
                        axes: Default::default(),
                    };
                    model.joint_names().count()
                ],
                drivers: n_drivers,
            },
        }
    }

    /// Column names, `t` first.
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The indices of the reaction and driver-effort columns (`<joint>.fx`, …, `<driver>.effort`).
    pub fn reaction_columns(&self) -> std::ops::Range<usize> {
        self.first_reaction..self.names.len() - TRAILING_COLUMNS.len()
    }

    /// Appends the row of sample `s` (one number per column) to `row`: positions and velocities,
    /// the reactions from the sample's multipliers, energy and constraint violations.
    ///
    /// # Panics
    /// When `model` is not the model these rows were made for (another kind of model).
    pub fn push(&mut self, model: &Mechanism, s: &Sample<'_>, row: &mut Vec<f64>) {
        row.push(s.t);
        match (&mut self.scratch, model) {
            (
                Scratch::Planar {
                    roles,
                    values,
                    reactions,
                },
                Mechanism::Planar(model),
            ) => {
                let sys = model.constraints();
                sys.evaluate(s.t, s.q, s.qd, values);
                sys.reactions(s.q, values, s.lambda, reactions);
                for i in 0..s.q.len() / 3 {
                    row.extend_from_slice(&s.q[3 * i..3 * i + 3]);
                    row.extend_from_slice(&s.qd[3 * i..3 * i + 3]);
                }
                for (r, role) in reactions.iter().zip(roles.iter()) {
                    match role {
                        ConstraintRole::Joint { carries_torque } => {
                            row.extend_from_slice(&[r.force.x, r.force.y]);
                            if *carries_torque {
                                row.push(r.torque);
                            }
                        }
                        ConstraintRole::Driver => row.push(r.effort.unwrap_or(f64::NAN)),
                    }
                }
            }
            (Scratch::Spatial { reactions, drivers }, Mechanism::Spatial(model)) => {
                for i in 0..model.bodies().len() {
                    let f = Frame::of(i, s.q, s.qd);
                    row.extend_from_slice(&s.q[7 * i..7 * i + 7]);
                    row.extend(f.v.iter().chain(f.w.iter()));
                }
                model.reactions_into(s.t, s.q, s.lambda, reactions);
                for r in reactions.iter() {
                    row.extend(r.force.iter().chain(r.moment.iter()));
                }
                let first = s.lambda.len() - *drivers;
                row.extend(s.lambda[first..].iter().map(|l| -l));
            }
            _ => panic!("output rows made for another kind of model"),
        }
        row.extend_from_slice(&[s.energy, s.constraint_violation, s.velocity_violation]);
    }
}

/// The last columns of every row.
const TRAILING_COLUMNS: [&str; 3] = ["energy", "constraint_violation", "velocity_violation"];

/// A run's output in memory: named columns, one row per output sample (row-major).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Table {
    /// Column names, `t` first.
    pub columns: Vec<String>,
    /// `rows × columns.len()` numbers, row after row.
    pub data: Vec<f64>,
}

impl Table {
    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.data.len().checked_div(self.columns.len()).unwrap_or(0)
    }

    /// Index of column `name`.
    pub fn index(&self, name: &str) -> Option<usize> {
        self.columns.iter().position(|c| c == name)
    }

    /// The values of column `name`, one per row, or `None` when there is no such column.
    pub fn column(&self, name: &str) -> Option<Vec<f64>> {
        let k = self.index(name)?;
        Some(self.data.iter().skip(k).step_by(self.columns.len()).copied().collect())
    }

    /// Row `i`.
    pub fn row(&self, i: usize) -> &[f64] {
        let w = self.columns.len();
        &self.data[i * w..(i + 1) * w]
    }

    /// The one-line error for a column that does not exist, listing the columns that do.
    pub fn unknown_column(&self, name: &str) -> String {
        crate::scene::unknown_name(
            "column",
            name,
            &self.columns.iter().map(String::as_str).collect::<Vec<_>>(),
        )
    }
}

/// Collects the samples of a run of `model` into a [`Table`].
#[derive(Debug, Clone)]
pub struct Recorder {
    rows: Rows,
    table: Table,
}

impl Recorder {
    /// An empty table with the columns of `model`.
    pub fn new(model: &Mechanism) -> Self {
        let rows = Rows::new(model);
        let table = Table {
            columns: rows.names().to_vec(),
            data: Vec::new(),
        };
        Recorder { rows, table }
    }

    /// Appends sample `s`.
    pub fn record(&mut self, model: &Mechanism, s: &Sample<'_>) {
        self.rows.push(model, s, &mut self.table.data);
    }

    /// The table so far.
    pub fn table(&self) -> &Table {
        &self.table
    }

    /// The table.
    pub fn into_table(self) -> Table {
        self.table
    }
}
