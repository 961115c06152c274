//! `dalembert trade`: the speed–accuracy trade of every formulation × integrator × constraint
//! treatment × step (or tolerance) on one scene, measured against a tight reference run.

use dalembert::output::shortest;
use dalembert::trade::{trade_cancellable, TradeGrid, TradeRun};
use plotters::prelude::*;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `trade`.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML).
    scene: PathBuf,
    /// End time of every run (s); default the scene's, at most 5 s.
    #[arg(long, allow_hyphen_values = true)]
    end: Option<f64>,
    /// Comparison interval (s); default the larger of the scene's output interval and the largest
    /// step (a fixed step is never longer than the interval between samples).
    #[arg(long, allow_hyphen_values = true)]
    every: Option<f64>,
    /// Formulations to try (comma-separated), and `joint`: the scene in joint coordinates (a
    /// spatial tree of revolute and prismatic joints; dropped from the default for other models).
    #[arg(long, value_delimiter = ',', default_values_t = TradeGrid::default().formulations)]
    formulations: Vec<String>,
    /// Integrators to try (default: every registered method).
    #[arg(long, value_delimiter = ',', default_values_t = registry_names(&dalembert::integrators::method_names()))]
    integrators: Vec<String>,
    /// Stabilizations for the fixed-step methods that do not keep the constraints themselves.
    #[arg(long, alias = "treatments", value_delimiter = ',', default_values_t = registry_names(dalembert::integrators::Stabilization::NAMES))]
    stabilizations: Vec<String>,
    /// Steps of the fixed-step methods (s).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1e-2,3e-3,1e-3,3e-4",
        allow_hyphen_values = true
    )]
    steps: Vec<f64>,
    /// Tolerances of the adaptive method (rtol = atol).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "1e-4,1e-6,1e-8,1e-10",
        allow_hyphen_values = true
    )]
    tolerances: Vec<f64>,
    /// Folder for trade.csv, trade.md and work-precision.svg.
    #[arg(long, default_value = "trade")]
    output: PathBuf,
}

fn registry_names(names: &[&str]) -> Vec<String> {
    names.iter().map(|s| s.to_string()).collect()
}

pub fn run(a: Args) -> Result<(), String> {
    // Named by the flag here; the library names the grid field.
    for (values, flag) in [(&a.steps, "--steps"), (&a.tolerances, "--tolerances")] {
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(format!("{flag}: every value must be positive and finite, got {v}"));
        }
    }
    let scene = crate::paths::load_scene(&a.scene)?;
    let grid = TradeGrid {
        formulations: a.formulations,
        integrators: a.integrators,
        stabilizations: a.stabilizations,
        steps: a.steps,
        tolerances: a.tolerances,
        end: a.end,
        every: a.every,
    };
    let tty = std::io::IsTerminal::is_terminal(&std::io::stderr());
    let t = trade_cancellable(
        &scene,
        &grid,
        &mut |done, _| {
            if tty {
                eprint!("\r{done} runs");
            }
        },
        crate::interrupt_flag(),
    )?;
    eprintln!();
    outln!(
        "scene        {} ({} s, compared every {} s against {})",
        scene.name,
        t.end,
        t.every,
        t.reference
    );
    let runs = &t.runs;
    std::fs::create_dir_all(&a.output).map_err(|e| format!("{}: {e}", a.output.display()))?;
    write_csv(&a.output.join("trade.csv"), runs)?;
    write_markdown(
        &a.output.join("trade.md"),
        &scene.name,
        t.end,
        &t.reference,
        runs,
        &t.front,
    )?;
    plot(&a.output.join("work-precision.svg"), &scene.name, runs, &t.front)?;
    outln!("\nbest method per accuracy band (fastest run whose error is within the band):");
    for band in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10] {
        match t.best_within(band) {
            Some(r) => outln!(
                "  error ≤ {band:.0e}: {} ({} = {:e}), {:.2} ms, error {:.1e}",
                r.method,
                if r.method.contains("dopri5") { "tol" } else { "h" },
                r.parameter,
                r.time_s * 1e3,
                r.error.unwrap_or(f64::NAN)
            ),
            None => outln!("  error ≤ {band:.0e}: no run of the grid"),
        }
    }
    let failed = runs.iter().filter(|r| r.error.is_none()).count();
    outln!(
        "\n{} runs ({} failed); wrote {}/trade.csv, trade.md, work-precision.svg",
        runs.len(),
        failed,
        a.output.display()
    );
    if t.interrupted {
        return Err(format!(
            "interrupted: {} runs of the grid made (the last stopped at its next step); the files hold them",
            runs.len()
        ));
    }
    Ok(())
}

fn write_csv(path: &std::path::Path, runs: &[TradeRun]) -> Result<(), String> {
    let mut s =
        String::from("method,parameter,time_s,evaluations,error,max_constraint_violation,max_energy_change,status\n");
    for r in runs {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{}",
            r.method,
            shortest(r.parameter),
            shortest(r.time_s),
            r.evaluations,
            r.error.map_or("".into(), shortest),
            shortest(r.constraint),
            shortest(r.energy),
            r.status.replace(',', ";")
        );
    }
    std::fs::write(path, s).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_markdown(
    path: &std::path::Path,
    name: &str,
    end: f64,
    reference: &str,
    runs: &[TradeRun],
    front: &[usize],
) -> Result<(), String> {
    let mut s = format!(
        "# Speed–accuracy trade: {name}\n\n{end} s of simulation; error = largest deviation of any coordinate or velocity from {reference}, at every comparison time. ★ = on the Pareto front.\n\n| method | h or tol | time [ms] | evaluations | error | max \\|C\\| | max \\|ΔE\\| [J] |\n|---|---|---|---|---|---|---|\n"
    );
    let mut order: Vec<usize> = (0..runs.len()).collect();
    order.sort_by(|&a, &b| {
        runs[a]
            .error
            .unwrap_or(f64::INFINITY)
            .total_cmp(&runs[b].error.unwrap_or(f64::INFINITY))
    });
    for i in order {
        let r = &runs[i];
        let star = if front.contains(&i) { " ★" } else { "" };
        match r.error {
            Some(e) => {
                let _ = writeln!(
                    s,
                    "| {}{star} | {:e} | {:.2} | {} | {:.1e} | {:.1e} | {:.1e} |",
                    r.method,
                    r.parameter,
                    r.time_s * 1e3,
                    r.evaluations,
                    e,
                    r.constraint,
                    r.energy
                );
            }
            None => {
                let _ = writeln!(s, "| {} | {:e} | failed: {} | | | | |", r.method, r.parameter, r.status);
            }
        }
    }
    std::fs::write(path, s).map_err(|e| format!("{}: {e}", path.display()))
}

fn plot(path: &std::path::Path, name: &str, runs: &[TradeRun], front: &[usize]) -> Result<(), String> {
    let ok: Vec<&TradeRun> = runs
        .iter()
        .filter(|r| r.error.is_some_and(|e| e > 0.0) && r.time_s > 0.0)
        .collect();
    if ok.is_empty() {
        return Err("no successful run to plot".into());
    }
    let (t0, t1) = ok
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), r| (a.min(r.time_s), b.max(r.time_s)));
    let (e0, e1) = ok.iter().fold((f64::INFINITY, 0.0f64), |(a, b), r| {
        let e = r.error.unwrap_or(1.0).max(1e-16);
        (a.min(e), b.max(e))
    });
    let root = SVGBackend::new(path, (1200, 700)).into_drawing_area();
    root.fill(&WHITE).map_err(|e| e.to_string())?;
    let (left, right) = root.split_horizontally(880);
    let mut chart = ChartBuilder::on(&left)
        .caption(format!("work–precision: {name}"), ("sans-serif", 22))
        .margin(16)
        .x_label_area_size(45)
        .y_label_area_size(80)
        .build_cartesian_2d((t0 / 1.5..t1 * 1.5).log_scale(), (e0 / 3.0..e1 * 3.0).log_scale())
        .map_err(|e| e.to_string())?;
    chart
        .configure_mesh()
        .x_desc("wall time of the integration loop [s]")
        .y_desc("max error against the reference")
        .y_label_formatter(&|v| format!("{v:.0e}"))
        .x_label_formatter(&|v| format!("{v:.0e}"))
        .draw()
        .map_err(|e| e.to_string())?;
    let mut methods: Vec<&str> = ok.iter().map(|r| r.method.as_str()).collect();
    methods.sort_unstable();
    methods.dedup();
    let color_of = |i: usize| HSLColor(i as f64 / methods.len().max(1) as f64, 0.85, 0.42);
    for (i, m) in methods.iter().enumerate() {
        let mut pts: Vec<(f64, f64)> = ok
            .iter()
            .filter(|r| r.method == *m)
            .map(|r| (r.time_s, r.error.unwrap_or(1.0).max(1e-16)))
            .collect();
        pts.sort_by(|a, b| a.0.total_cmp(&b.0));
        let color = color_of(i);
        chart
            .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
            .map_err(|e| e.to_string())?;
        chart
            .draw_series(pts.into_iter().map(|p| Circle::new(p, 3, color.filled())))
            .map_err(|e| e.to_string())?;
    }
    let fp: Vec<(f64, f64)> = front
        .iter()
        .map(|&i| (runs[i].time_s, runs[i].error.unwrap_or(1.0).max(1e-16)))
        .collect();
    chart
        .draw_series(LineSeries::new(fp.clone(), BLACK.stroke_width(1)))
        .map_err(|e| e.to_string())?;
    chart
        .draw_series(fp.into_iter().map(|p| Circle::new(p, 7, BLACK.stroke_width(2))))
        .map_err(|e| e.to_string())?;
    // Legend, beside the chart.
    let font = ("sans-serif", 13).into_font();
    let entries = methods
        .iter()
        .enumerate()
        .map(|(i, m)| (m.to_string(), color_of(i).to_rgba()));
    let all = std::iter::once(("Pareto front (circled)".to_string(), BLACK.to_rgba())).chain(entries);
    for (k, (label, color)) in all.enumerate() {
        let y = 40 + 20 * k as i32;
        right
            .draw(&PathElement::new(vec![(8, y), (34, y)], color.stroke_width(3)))
            .map_err(|e| e.to_string())?;
        right
            .draw(&Text::new(label, (42, y - 7), font.clone()))
            .map_err(|e| e.to_string())?;
    }
    root.present().map_err(|e| e.to_string())
}
