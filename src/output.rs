//! Streamed CSV output of a run.
//!
//! Columns: `t`; for every body `<body>.x`, `.y`, `.angle`, `.vx`, `.vy`, `.omega` (reference point,
//! the centre of mass unless the body says otherwise; angles continuous, never wrapped); for every
//! joint `<joint>.fx`, `.fy` (reaction on the joint's first body from its second, global) and
//! `<joint>.torque` where the joint carries one; for every driver `<driver>.effort`; then `energy`,
//! `constraint_violation`, `velocity_violation`. Rows are written as the run produces them.

use dalembert_constraints::{ConstraintRole, ConstraintValues, Model, Reaction};
use dalembert_integrators::Sample;
use std::io::{self, Write};

/// Writes samples of a run of `model` as CSV rows.
pub struct CsvOutput<W: Write> {
    out: W,
    values: ConstraintValues,
    reactions: Vec<Reaction>,
    roles: Vec<ConstraintRole>,
    error: Option<io::Error>,
}

impl<W: Write> CsvOutput<W> {
    /// Writes the header for `model` and returns the writer.
    pub fn new(model: &Model, mut out: W) -> io::Result<Self> {
        let mut cols = vec!["t".to_string()];
        for b in model.bodies() {
            for c in ["x", "y", "angle", "vx", "vy", "omega"] {
                cols.push(format!("{}.{c}", b.name));
            }
        }
        let sys = model.constraints();
        let roles: Vec<ConstraintRole> = sys.constraints().iter().map(|c| c.role()).collect();
        for (c, role) in sys.constraints().iter().zip(&roles) {
            match role {
                ConstraintRole::Joint { carries_torque } => {
                    cols.push(format!("{}.fx", c.name()));
                    cols.push(format!("{}.fy", c.name()));
                    if *carries_torque {
                        cols.push(format!("{}.torque", c.name()));
                    }
                }
                ConstraintRole::Driver => cols.push(format!("{}.effort", c.name())),
            }
        }
        cols.extend(["energy", "constraint_violation", "velocity_violation"].map(String::from));
        writeln!(out, "{}", cols.join(","))?;
        Ok(CsvOutput {
            out,
            values: sys.values(),
            reactions: vec![Reaction::default(); roles.len()],
            roles,
            error: None,
        })
    }

    /// Writes one sample. I/O errors are kept and reported by [`CsvOutput::finish`].
    pub fn write(&mut self, model: &Model, s: &Sample<'_>) {
        if self.error.is_some() {
            return;
        }
        let sys = model.constraints();
        sys.evaluate(s.t, s.q, s.qd, &mut self.values);
        sys.reactions(s.q, &self.values, s.lambda, &mut self.reactions);
        if let Err(e) = self.write_row(s) {
            self.error = Some(e);
        }
    }

    fn write_row(&mut self, s: &Sample<'_>) -> io::Result<()> {
        write!(self.out, "{}", s.t)?;
        for i in 0..s.q.len() / 3 {
            let k = 3 * i;
            write!(
                self.out,
                ",{},{},{},{},{},{}",
                s.q[k],
                s.q[k + 1],
                s.q[k + 2],
                s.qd[k],
                s.qd[k + 1],
                s.qd[k + 2]
            )?;
        }
        for (r, role) in self.reactions.iter().zip(&self.roles) {
            match role {
                ConstraintRole::Joint { carries_torque } => {
                    write!(self.out, ",{},{}", r.force.x, r.force.y)?;
                    if *carries_torque {
                        write!(self.out, ",{}", r.torque)?;
                    }
                }
                ConstraintRole::Driver => write!(self.out, ",{}", r.effort.unwrap_or(f64::NAN))?,
            }
        }
        writeln!(
            self.out,
            ",{},{},{}",
            s.energy, s.constraint_violation, s.velocity_violation
        )
    }

    /// Flushes and returns the first I/O error met, if any.
    pub fn finish(mut self) -> io::Result<W> {
        if let Some(e) = self.error.take() {
            return Err(e);
        }
        self.out.flush()?;
        Ok(self.out)
    }
}
