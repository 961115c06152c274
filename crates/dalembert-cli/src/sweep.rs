//! `dalembert sweep`: one scene run for every combination of values, on all cores.

use dalembert::sweep::{cartesian, split_list, sweep_streaming, Output, SweepCsv, SweepRow};
use dalembert::SceneValue;
use std::collections::BTreeMap;
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::Instant;

/// Arguments of `sweep`.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML).
    scene: PathBuf,
    /// A parameter and its values, `path=v1,v2,…` (e.g. `bodies.slider.mass=1,2,4`); repeat for
    /// more parameters: every combination is run.
    #[arg(long = "set", required = true, allow_hyphen_values = true)]
    set: Vec<String>,
    /// End time of every run (s); default the scene's.
    #[arg(long, allow_hyphen_values = true)]
    end: Option<f64>,
    /// Outputs (comma-separated): a column's final value (`slider.x`), `max:`/`min:`/`mean:`/
    /// `maxabs:` a column, or `statistics.steps`, `statistics.evaluations`,
    /// `statistics.max_constraint_violation`, `statistics.max_energy_change`. Default: the final
    /// value of every position column.
    #[arg(long, value_delimiter = ',')]
    outputs: Vec<String>,
    /// Threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Write one row per run as CSV (parameters, outputs, wall time, error).
    #[arg(long)]
    output: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<(), String> {
    let scene = crate::paths::load_scene(&a.scene)?;
    if let Some(end) = a.end {
        if !(end.is_finite() && end > 0.0) {
            return Err(format!("--end must be positive, got {end}"));
        }
    }
    if a.threads == Some(0) {
        return Err("--threads must be at least 1".into());
    }
    let mut parameters = Vec::new();
    for s in &a.set {
        let (path, values) = s
            .split_once('=')
            .ok_or_else(|| format!("--set '{s}': expected path=v1,v2,… (e.g. bodies.slider.mass=1,2,4)"))?;
        let values: Vec<SceneValue> = split_list(values).into_iter().map(SceneValue::parse).collect();
        // Each path checked against the scene, so that a typo fails before any run (a value that
        // breaks a rule fails its own runs only).
        scene.check_path(path).map_err(|e| format!("--set: {e}"))?;
        parameters.push((path.to_string(), values));
    }
    let names: Vec<String> = if a.outputs.is_empty() {
        // Each body's position: x, y, angle (planar) or x, y, z (spatial).
        let labels = scene.model.kind().position_columns();
        scene
            .model
            .body_names()
            .iter()
            .flat_map(|b| labels.iter().map(move |c| format!("{b}.{c}")))
            .collect()
    } else {
        a.outputs.clone()
    };
    let outputs = names
        .iter()
        .map(|n| Output::parse(&scene, n))
        .collect::<Result<Vec<_>, _>>()?;
    let runs = cartesian(&parameters);
    let paths: Vec<String> = parameters.iter().map(|(p, _)| p.clone()).collect();
    // The CSV is streamed in the order of the runs: the header now, each row as soon as it and
    // every row before it have ended (those that end early wait in `pending`). A sweep stopped by
    // a signal writes every row; one killed outright leaves the rows up to its first unfinished run.
    let sink: Box<dyn std::io::Write + Send> = match &a.output {
        Some(p) => {
            crate::paths::refuse_overwriting(p, &[&a.scene])?;
            Box::new(std::fs::File::create(p).map_err(|e| format!("{}: {e}", p.display()))?)
        }
        None => Box::new(std::io::stdout()),
    };
    let where_to = a
        .output
        .as_ref()
        .map_or("stdout".to_string(), |p| p.display().to_string());
    let csv = SweepCsv::new(sink, &paths, &names).map_err(|e| format!("{where_to}: {e}"))?;
    let writer = Mutex::new(Streamed {
        csv,
        failure: None,
        next: 0,
        pending: BTreeMap::new(),
    });
    let write_row = |k: usize, row: &SweepRow| {
        let mut w = writer.lock().unwrap_or_else(|p| p.into_inner());
        w.pending.insert(k, row.clone());
        w.write_ready();
    };
    let start = Instant::now();
    let rows = sweep_streaming(
        &scene,
        &runs,
        a.end,
        &outputs,
        a.threads,
        crate::interrupt_flag(),
        &write_row,
    )?;
    let wall = start.elapsed().as_secs_f64();
    let w = writer.into_inner().unwrap_or_else(|p| p.into_inner());
    let write_error = w.failure.or_else(|| w.csv.finish().err());
    if let Some(e) = write_error {
        if e.kind() != std::io::ErrorKind::BrokenPipe || a.output.is_some() {
            return Err(format!("{where_to}: {e}"));
        }
    }
    let failed = rows.iter().filter(|r| r.error.is_some()).count();
    let busy: f64 = rows.iter().map(|r| r.wall_time).sum();
    eprintln!(
        "{} runs ({failed} failed) in {wall:.3} s on {} threads ({:.2} ms of work per run, speed-up {:.2}){}",
        rows.len(),
        a.threads.unwrap_or_else(rayon_threads),
        1e3 * busy / rows.len().max(1) as f64,
        busy / wall.max(1e-12),
        a.output
            .as_ref()
            .map(|p| format!("; wrote {}", p.display()))
            .unwrap_or_default()
    );
    if crate::interrupt_flag().load(std::sync::atomic::Ordering::Relaxed) {
        let stopped = rows
            .iter()
            .filter(|r| r.error.as_deref().is_some_and(|e| e.starts_with("interrupted")))
            .count();
        let cancelled = rows
            .iter()
            .filter(|r| r.error.as_deref() == Some(dalembert::sweep::CANCELLED))
            .count();
        return Err(format!(
            "interrupted: {} runs finished, {stopped} stopped at their next step (rows marked \"interrupted at t = …\"), {cancelled} not started (marked \"cancelled\")",
            rows.len() - stopped - cancelled
        ));
    }
    if failed > 0 {
        let first = rows.iter().find_map(|r| r.error.as_deref()).unwrap_or_default();
        return Err(format!(
            "{failed} of {} runs failed (the first: {}); their rows hold the error",
            rows.len(),
            dalembert::scene::one_line(first)
        ));
    }
    Ok(())
}

/// The sweep's CSV as it is streamed: rows written in run order as soon as each and all before it
/// have ended.
struct Streamed<W: std::io::Write> {
    csv: SweepCsv<W>,
    /// The first write error (a closed stdout ends the output, not the sweep).
    failure: Option<std::io::Error>,
    /// The index of the next row to write.
    next: usize,
    /// Rows ended before some row ahead of them.
    pending: BTreeMap<usize, SweepRow>,
}

impl<W: std::io::Write> Streamed<W> {
    fn write_ready(&mut self) {
        while let Some(row) = self.pending.remove(&self.next) {
            self.next += 1;
            if self.failure.is_none() {
                if let Err(e) = self.csv.row(&row) {
                    self.failure = Some(e);
                }
            }
        }
    }
}

fn rayon_threads() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}
