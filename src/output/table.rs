//! The columns of a run's output, and a run kept in memory (the Python package, sweeps).
//!
//! [`Rows`] names the columns of a model's output and fills one row of numbers from a sample; the
//! CSV writer and the in-memory [`Table`] both use it, so a column means the same thing in a file,
//! a numpy array and a sweep.

use crate::mechanism::{ColumnWriter, Mechanism};
use dalembert_integrators::Sample;

/// The output columns of one model and the scratch space to compute a row (allocation-free after
/// construction).
#[derive(Debug)]
pub struct Rows {
    names: Vec<String>,
    /// Index of the first reaction or effort column.
    first_reaction: usize,
    columns: Box<dyn ColumnWriter>,
}

impl Clone for Rows {
    fn clone(&self) -> Self {
        Rows {
            names: self.names.clone(),
            first_reaction: self.first_reaction,
            columns: self.columns.boxed_clone(),
        }
    }
}

impl Rows {
    /// The columns of `model` (see the module documentation of [`crate::output`]).
    pub fn new(model: &Mechanism) -> Self {
        let columns = model.columns();
        let mut names = vec!["t".to_string()];
        names.extend(columns.body_columns());
        let first_reaction = names.len();
        names.extend(columns.reaction_columns());
        names.extend(TRAILING_COLUMNS.map(String::from));
        Rows {
            names,
            first_reaction,
            columns,
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

    /// The indices of the position columns and of the velocity columns of `model` (its bodies'
    /// columns, each body's positions first: `slider.x`, `slider.y`, `slider.angle`, then
    /// `slider.vx`, …), in the order of `q` and `q̇`.
    pub fn state_columns(&self, model: &Mechanism) -> (Vec<usize>, Vec<usize>) {
        let bodies = model.num_bodies();
        let per_q = model.num_positions() / bodies.max(1);
        let per_v = model.num_velocities() / bodies.max(1);
        let (mut q, mut v) = (Vec::new(), Vec::new());
        for b in 0..bodies {
            let first = 1 + b * (per_q + per_v);
            q.extend(first..first + per_q);
            v.extend(first + per_q..first + per_q + per_v);
        }
        (q, v)
    }

    /// Appends the row of sample `s` (one number per column) to `row`: positions and velocities,
    /// the reactions from the sample's multipliers, energy and constraint violations.
    pub fn push(&mut self, s: &Sample<'_>, row: &mut Vec<f64>) {
        row.push(s.t);
        self.columns.push(s, row);
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
    pub fn record(&mut self, s: &Sample<'_>) {
        self.rows.push(s, &mut self.table.data);
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
