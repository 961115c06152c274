//! Streamed CSV output of a run.
//!
//! Columns: `t`; for every body `<body>.x`, `.y`, `.angle`, `.vx`, `.vy`, `.omega` (reference point,
//! the centre of mass unless the body says otherwise; angles continuous, never wrapped); for every
//! joint `<joint>.fx`, `.fy` (reaction on the joint's first body from its second, global) and
//! `<joint>.torque` where the joint carries one; for every driver `<driver>.effort`; then `energy`,
//! `constraint_violation`, `velocity_violation`. Rows are written as the run produces them.

mod read;
mod table;

pub use crate::mechanism::{PLANAR_BODY_COLUMNS, SPATIAL_BODY_COLUMNS, SPATIAL_JOINT_COLUMNS};
pub use read::{no_column, read_columns, read_header, ResultCsvError, ResultTable};
pub use table::{Recorder, Rows, Table};

use crate::mechanism::Mechanism;
use dalembert_integrators::Sample;
use std::io::{self, Write};
use std::time::{Duration, Instant};

/// Longest time a complete row may wait in the buffer before it is flushed: a run killed by a
/// signal that cannot be caught loses at most this much of its output, and never leaves half a row.
const FLUSH_EVERY: Duration = Duration::from_millis(250);

/// Writes samples of a run of `model` as CSV rows (RFC 4180: names with commas, quotes or line
/// breaks are quoted; numbers in shortest round-trip form).
pub struct CsvOutput<W: Write> {
    out: W,
    rows_of: Rows,
    numbers: Vec<f64>,
    error: Option<io::Error>,
    rows: u64,
    last_time: Option<f64>,
    flushed: Instant,
    /// The row being formatted: handed to the writer whole, so that the file receives complete
    /// rows only (a buffered writer passes on whole rows when it fills).
    row: Vec<u8>,
}

/// Writes `x` in shortest round-trip form: plain decimals for magnitudes from 1e-5 to 1e16,
/// scientific notation outside (so 1e-300 takes 6 characters, not 302). Both read back exactly.
pub fn write_number(w: &mut impl Write, x: f64) -> io::Result<()> {
    write!(w, "{}", dalembert_system::Shortest(x))
}

/// `x` in the shortest round-trip form of [`write_number`], as a string: for every number a
/// message, a table or a file prints.
pub fn shortest(x: f64) -> String {
    dalembert_system::Shortest(x).to_string()
}

/// `x` in fixed-point notation with `decimals` digits after the point, right-aligned in `width`
/// characters, as the command line's tables print it: a value that rounds to zero prints without
/// a sign (`0.000000`, never `-0.000000`), and one too large for fixed point (past 1e15) in its
/// shortest form.
pub fn fixed(x: f64, width: usize, decimals: usize) -> String {
    if x.is_finite() && x.abs() >= 1e15 {
        return format!("{:>width$}", shortest(x));
    }
    let text = format!("{x:.decimals$}");
    let text = match text.strip_prefix('-') {
        Some(rest) if rest.chars().all(|c| c == '0' || c == '.') => rest.to_string(),
        _ => text,
    };
    format!("{text:>width$}")
}

impl<W: Write> CsvOutput<W> {
    /// Writes the header for `model` and returns the writer.
    pub fn new(model: &Mechanism, out: W) -> io::Result<Self> {
        Self::with_columns(model, &[], out)
    }

    /// Writes the header for `model` followed by the `extra` columns (a run's sensitivities,
    /// given to [`CsvOutput::write_with`]) and returns the writer.
    pub fn with_columns(model: &Mechanism, extra: &[String], mut out: W) -> io::Result<Self> {
        let rows_of = Rows::new(model);
        {
            let mut header = csv::WriterBuilder::new()
                .terminator(csv::Terminator::Any(b'\n'))
                .from_writer(&mut out);
            header.write_record(rows_of.names().iter().chain(extra))?;
            header.flush()?;
        }
        out.flush()?;
        Ok(CsvOutput {
            out,
            numbers: Vec::with_capacity(rows_of.names().len() + extra.len()),
            rows_of,
            error: None,
            rows: 0,
            last_time: None,
            flushed: Instant::now(),
            row: Vec::new(),
        })
    }

    /// Rows written so far.
    pub fn rows(&self) -> u64 {
        self.rows
    }

    /// Time of the last row written.
    pub fn last_time(&self) -> Option<f64> {
        self.last_time
    }

    /// Writes one sample. I/O errors are kept and reported by [`CsvOutput::finish`].
    pub fn write(&mut self, s: &Sample<'_>) {
        self.write_with(s, &[]);
    }

    /// Writes one sample and the values of the extra columns ([`CsvOutput::with_columns`]).
    pub fn write_with(&mut self, s: &Sample<'_>, extra: &[f64]) {
        if self.error.is_some() {
            return;
        }
        self.numbers.clear();
        self.rows_of.push(s, &mut self.numbers);
        self.numbers.extend_from_slice(extra);
        let written = self.write_row().and_then(|()| {
            self.rows += 1;
            self.last_time = Some(s.t);
            if self.flushed.elapsed() >= FLUSH_EVERY {
                self.flushed = Instant::now();
                self.out.flush()?;
            }
            Ok(())
        });
        if let Err(e) = written {
            self.error = Some(e);
        }
    }

    fn write_row(&mut self) -> io::Result<()> {
        let out = &mut self.row;
        out.clear();
        for (k, &v) in self.numbers.iter().enumerate() {
            if k > 0 {
                out.write_all(b",")?;
            }
            write_number(out, v)?;
        }
        out.write_all(b"\n")?;
        self.out.write_all(&self.row)
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
