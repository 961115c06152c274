//! Parameter sweeps: many runs of one scene with values changed by path
//! ([`Scene::with_values`]), on all local cores (rayon). One run's failure is its row's error and
//! never loses the other rows. The Python package distributes the same runs over any executor
//! (`docs/sweeps.md`).

use crate::output::Rows;
use crate::{Scene, SceneValue};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

/// One run's assignments: `(path, value)` pairs.
pub type Assignment = Vec<(String, SceneValue)>;

/// How an output column is summarized over a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Summary {
    /// The value at the end of the run.
    Final,
    /// The largest value over the output samples.
    Max,
    /// The smallest value over the output samples.
    Min,
    /// The mean over the output samples.
    Mean,
    /// The largest absolute value over the output samples.
    MaxAbs,
}

/// A run statistic a sweep can report.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum Statistic {
    /// Accepted steps.
    Steps,
    /// Right-hand-side evaluations.
    Evaluations,
    /// Largest `|C|` after any step.
    MaxConstraintViolation,
    /// Largest `|E − E₀|` (J).
    MaxEnergyChange,
}

/// One requested output of a sweep, parsed from its name: `slider.x` (final value),
/// `max:slider.x`, `min:…`, `mean:…`, `maxabs:…`, or `statistics.steps`, `statistics.evaluations`,
/// `statistics.max_constraint_violation`, `statistics.max_energy_change`.
#[derive(Debug, Clone, PartialEq)]
pub enum Output {
    /// A column summarized over the run.
    Column {
        /// Index of the column in the output row.
        index: usize,
        /// How.
        summary: Summary,
    },
    /// A run statistic.
    Statistic(Statistic),
}

const STATISTICS: &[(&str, Statistic)] = &[
    ("statistics.steps", Statistic::Steps),
    ("statistics.evaluations", Statistic::Evaluations),
    ("statistics.max_constraint_violation", Statistic::MaxConstraintViolation),
    ("statistics.max_energy_change", Statistic::MaxEnergyChange),
];

impl Output {
    /// Parses `name` against the output columns of `scene`; the error is one line listing what
    /// exists.
    pub fn parse(scene: &Scene, name: &str) -> Result<Output, String> {
        if let Some(&(_, s)) = STATISTICS.iter().find(|(n, _)| *n == name) {
            return Ok(Output::Statistic(s));
        }
        let (summary, column) = match name.split_once(':') {
            Some(("max", c)) => (Summary::Max, c),
            Some(("min", c)) => (Summary::Min, c),
            Some(("mean", c)) => (Summary::Mean, c),
            Some(("maxabs", c)) => (Summary::MaxAbs, c),
            Some(("final", c)) => (Summary::Final, c),
            Some((s, _)) => {
                return Err(crate::scene::unknown_name(
                    "summary",
                    s,
                    &["final", "max", "min", "mean", "maxabs"],
                ))
            }
            None => (Summary::Final, name),
        };
        let rows = Rows::new(&scene.model);
        match rows.names().iter().position(|n| n == column) {
            Some(index) => Ok(Output::Column { index, summary }),
            None => {
                let mut known: Vec<&str> = rows.names().iter().map(String::as_str).collect();
                known.extend(STATISTICS.iter().map(|(n, _)| *n));
                Err(crate::scene::unknown_name("output", column, &known))
            }
        }
    }
}

/// One run of a sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    /// The values set for this run.
    pub assignment: Assignment,
    /// One number per requested output (NaN when the run failed).
    pub outputs: Vec<f64>,
    /// Wall time of the whole run, building the scene included (s).
    pub wall_time: f64,
    /// Why the run failed (the scene could not be built with these values, or the run stopped).
    pub error: Option<String>,
}

/// The cartesian product of `parameters` (`path`, values), the first parameter varying slowest.
pub fn cartesian(parameters: &[(String, Vec<SceneValue>)]) -> Vec<Assignment> {
    let mut out: Vec<Assignment> = vec![Vec::new()];
    for (path, values) in parameters {
        out = out
            .into_iter()
            .flat_map(|a| {
                values.iter().map(move |v| {
                    let mut b = a.clone();
                    b.push((path.clone(), v.clone()));
                    b
                })
            })
            .collect();
    }
    out
}

/// The error of a sweep's run that never started because the sweep was cancelled (a run stopped
/// part way says `interrupted at t = …`, the time it reached).
pub const CANCELLED: &str = "cancelled";

/// Runs `scene` with `assignment` to `end` (the scene's end when `None`) and summarizes `outputs`.
/// The run stops at its next step once `cancel` is set; its row's error then says
/// `interrupted at t = …`.
pub fn run_one(
    scene: &Scene,
    assignment: &Assignment,
    end: Option<f64>,
    outputs: &[Output],
    cancel: &AtomicBool,
) -> SweepRow {
    let start = Instant::now();
    let pairs: Vec<(&str, SceneValue)> = assignment.iter().map(|(p, v)| (p.as_str(), v.clone())).collect();
    let result = scene.with_values(&pairs).map_err(|e| e.to_string()).and_then(|s| {
        let mut sim = s.simulation();
        if let Some(end) = end {
            sim.end = end;
        }
        let mut rows = Rows::new(&s.model);
        let mut row = Vec::with_capacity(rows.names().len());
        let mut acc: Vec<(f64, usize)> = vec![(f64::NAN, 0); outputs.len()];
        let stats = sim
            .run_cancellable(
                &mut |smp| {
                    row.clear();
                    rows.push(smp, &mut row);
                    for (o, a) in outputs.iter().zip(acc.iter_mut()) {
                        if let Output::Column { index, summary } = o {
                            let v = row[*index];
                            a.0 = if a.1 == 0 {
                                if *summary == Summary::MaxAbs {
                                    v.abs()
                                } else {
                                    v
                                }
                            } else {
                                match summary {
                                    Summary::Final => v,
                                    Summary::Max => a.0.max(v),
                                    Summary::Min => a.0.min(v),
                                    Summary::Mean => a.0 + v,
                                    Summary::MaxAbs => a.0.max(v.abs()),
                                }
                            };
                            a.1 += 1;
                        }
                    }
                },
                cancel,
            )
            .map_err(|e| match e.interrupted_at() {
                Some(t) => format!("interrupted at t = {}", crate::output::shortest(t)),
                None => e.to_string(),
            })?;
        Ok(outputs
            .iter()
            .zip(&acc)
            .map(|(o, &(v, count))| match o {
                Output::Column {
                    summary: Summary::Mean, ..
                } => v / count as f64,
                Output::Column { .. } => v,
                Output::Statistic(Statistic::Steps) => stats.steps as f64,
                Output::Statistic(Statistic::Evaluations) => stats.evaluations as f64,
                Output::Statistic(Statistic::MaxConstraintViolation) => stats.max_constraint_violation,
                Output::Statistic(Statistic::MaxEnergyChange) => stats.max_energy_change,
            })
            .collect::<Vec<f64>>())
    });
    let (outputs, error) = match result {
        Ok(v) => (v, None),
        Err(e) => (vec![f64::NAN; outputs.len()], Some(e)),
    };
    SweepRow {
        assignment: assignment.clone(),
        outputs,
        wall_time: start.elapsed().as_secs_f64(),
        error,
    }
}

/// Runs every assignment on `threads` threads (all cores when `None`), in parallel, rows in the
/// order of `runs`. Once `cancel` is set, every run in progress stops at its next step (its row's
/// error `interrupted at t = …`) and a run not yet started is a row with the error
/// [`CANCELLED`].
pub fn sweep(
    scene: &Scene,
    runs: &[Assignment],
    end: Option<f64>,
    outputs: &[Output],
    threads: Option<usize>,
    cancel: &AtomicBool,
) -> Result<Vec<SweepRow>, String> {
    sweep_streaming(scene, runs, end, outputs, threads, cancel, &|_, _| {})
}

/// [`sweep`] that hands each row to `finished(index, row)` as soon as its run ends (from the
/// worker thread that ran it, in the order the runs finish; `index` is its place in `runs`), so
/// that a caller can write it at once.
pub fn sweep_streaming(
    scene: &Scene,
    runs: &[Assignment],
    end: Option<f64>,
    outputs: &[Output],
    threads: Option<usize>,
    cancel: &AtomicBool,
    finished: &(dyn Fn(usize, &SweepRow) + Sync),
) -> Result<Vec<SweepRow>, String> {
    use rayon::prelude::*;
    let work = || {
        runs.par_iter()
            .enumerate()
            .map(|(k, a)| {
                let row = if cancel.load(Ordering::Relaxed) {
                    SweepRow {
                        assignment: a.clone(),
                        outputs: vec![f64::NAN; outputs.len()],
                        wall_time: 0.0,
                        error: Some(CANCELLED.into()),
                    }
                } else {
                    run_one(scene, a, end, outputs, cancel)
                };
                finished(k, &row);
                row
            })
            .collect()
    };
    match threads {
        None => Ok(work()),
        Some(n) => rayon::ThreadPoolBuilder::new()
            .num_threads(n.max(1))
            .build()
            .map(|pool| pool.install(work))
            .map_err(|e| format!("cannot start {n} threads: {e}")),
    }
}

/// Writes sweep rows as CSV: one column per parameter path, one per output, `wall_time_s` and
/// `error` (empty for a run that finished). Numbers in shortest round-trip form.
pub fn write_csv(
    out: impl std::io::Write,
    parameters: &[String],
    outputs: &[String],
    rows: &[SweepRow],
) -> std::io::Result<()> {
    let mut w = SweepCsv::new(out, parameters, outputs)?;
    for r in rows {
        w.row(r)?;
    }
    w.finish()
}

/// A sweep's CSV written row by row (the header first), each row flushed as it is written: a
/// sweep that stops by any means leaves a well-formed file with every row finished so far.
pub struct SweepCsv<W: std::io::Write> {
    w: csv::Writer<W>,
    parameters: Vec<String>,
}

impl<W: std::io::Write> SweepCsv<W> {
    /// Writes the header: one column per parameter path, one per output, `wall_time_s`, `error`.
    pub fn new(out: W, parameters: &[String], outputs: &[String]) -> std::io::Result<Self> {
        let mut w = csv::WriterBuilder::new()
            .terminator(csv::Terminator::Any(b'\n'))
            .from_writer(out);
        let mut header: Vec<&str> = parameters.iter().map(String::as_str).collect();
        header.extend(outputs.iter().map(String::as_str));
        header.extend(["wall_time_s", "error"]);
        w.write_record(&header)?;
        w.flush()?;
        Ok(SweepCsv {
            w,
            parameters: parameters.to_vec(),
        })
    }

    /// Writes one row and flushes it.
    pub fn row(&mut self, r: &SweepRow) -> std::io::Result<()> {
        let number = |x: f64| crate::output::shortest(x);
        let mut rec: Vec<String> = self
            .parameters
            .iter()
            .map(|p| {
                r.assignment
                    .iter()
                    .find(|(q, _)| q == p)
                    .map(|(_, v)| match v {
                        SceneValue::Number(x) => number(*x),
                        SceneValue::Text(s) => s.clone(),
                        other => other.to_string(),
                    })
                    .unwrap_or_default()
            })
            .collect();
        rec.extend(r.outputs.iter().map(|&x| number(x)));
        rec.push(number(r.wall_time));
        rec.push(
            r.error
                .as_deref()
                .map(|e| crate::scene::one_line(e).into_owned())
                .unwrap_or_default(),
        );
        self.w.write_record(&rec)?;
        self.w.flush()
    }

    /// Flushes the file.
    pub fn finish(mut self) -> std::io::Result<()> {
        self.w.flush()
    }
}

/// Splits a command-line list `1,2,[0,-9.81]` at the commas outside brackets and quotes.
pub fn split_list(text: &str) -> Vec<&str> {
    let (mut depth, mut quoted, mut start) = (0i32, false, 0);
    let mut out = Vec::new();
    for (i, c) in text.char_indices() {
        match c {
            '"' => quoted = !quoted,
            '[' if !quoted => depth += 1,
            ']' if !quoted => depth -= 1,
            ',' if !quoted && depth == 0 => {
                out.push(text[start..i].trim());
                start = i + 1;
            }
            _ => {}
        }
    }
    out.push(text[start..].trim());
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_split_outside_brackets_and_quotes() {
        assert_eq!(split_list("1,2, 4"), ["1", "2", "4"]);
        assert_eq!(split_list("[0,-9.81],[0,-1.62]"), ["[0,-9.81]", "[0,-1.62]"]);
        assert_eq!(split_list("\"a,b\",c"), ["\"a,b\"", "c"]);
    }

    #[test]
    fn values_read_as_toml_or_text() {
        assert_eq!(SceneValue::parse("2"), SceneValue::Integer(2));
        assert_eq!(SceneValue::parse("1.5e3"), SceneValue::Number(1500.0));
        assert_eq!(SceneValue::parse("rk4"), SceneValue::Text("rk4".into()));
        assert_eq!(
            SceneValue::parse("[0, -9.81]"),
            SceneValue::List(vec![SceneValue::Integer(0), SceneValue::Number(-9.81)])
        );
    }

    #[test]
    fn cartesian_product_first_path_slowest() {
        let p = vec![
            ("a".to_string(), vec![SceneValue::Integer(1), SceneValue::Integer(2)]),
            (
                "b".to_string(),
                vec![SceneValue::Integer(3), SceneValue::Integer(4), SceneValue::Integer(5)],
            ),
        ];
        let runs = cartesian(&p);
        assert_eq!(runs.len(), 6);
        assert_eq!(
            runs[1],
            vec![
                ("a".into(), SceneValue::Integer(1)),
                ("b".into(), SceneValue::Integer(4))
            ]
        );
        assert_eq!(runs[3][0].1, SceneValue::Integer(2));
    }
}
