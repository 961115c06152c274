//! `dalembert trade`: the speed–accuracy trade of every formulation × integrator × constraint
//! treatment × step (or tolerance) on one scene, measured against a tight reference run.

use dalembert::integrators::{ConstraintTreatment, IntegratorOptions, Method};
use dalembert::scene::{unknown_name, IntegratorKind, StabilizationKind};
use dalembert::{FormulationKind, Scene};
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
    /// Formulations to try (comma-separated).
    #[arg(long, value_delimiter = ',', default_value = "augmented,embedding,amalgamated")]
    formulations: Vec<String>,
    /// Integrators to try.
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "symplectic-euler,rk4,dopri5,generalized-alpha"
    )]
    integrators: Vec<String>,
    /// Constraint treatments for the fixed-step explicit methods.
    #[arg(long, value_delimiter = ',', default_value = "none,baumgarte,projection")]
    treatments: Vec<String>,
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

/// One run of the grid.
struct Run {
    method: String,
    parameter: f64,
    time_s: f64,
    evaluations: u64,
    error: Option<f64>,
    constraint: f64,
    energy: f64,
    status: String,
}

/// Wall time, evaluations, largest |C| and largest energy change of a finished run.
type Outcome = (f64, u64, f64, f64);

/// Samples `[q, q̇]` at the comparison times, and the outcome or the failure.
fn samples(
    scene: &Scene,
    kind: FormulationKind,
    opts: IntegratorOptions,
    end: f64,
) -> (Vec<Vec<f64>>, Result<Outcome, String>) {
    let mut sim = scene.simulation();
    sim.formulation = kind;
    sim.integrator = opts;
    sim.end = end;
    let mut out = Vec::new();
    let res = sim.run(&mut |s| out.push([s.q, s.qd].concat()));
    let r = res
        .map(|st| {
            (
                st.wall_time.as_secs_f64(),
                st.evaluations,
                st.max_constraint_violation,
                st.max_energy_change,
            )
        })
        .map_err(|e| e.to_string());
    (out, r)
}

fn grid(a: &Args) -> Result<Vec<(FormulationKind, String, IntegratorOptions, f64)>, String> {
    let mut g = Vec::new();
    for f in &a.formulations {
        let kind = FormulationKind::parse(f).ok_or_else(|| unknown_name("formulation", f, FormulationKind::NAMES))?;
        for i in &a.integrators {
            let integ = IntegratorKind::parse(i).ok_or_else(|| unknown_name("integrator", i, IntegratorKind::NAMES))?;
            match integ {
                IntegratorKind::Dopri5 => {
                    for &tol in &a.tolerances {
                        let m = Method::DormandPrince { rtol: tol, atol: tol };
                        let mut o = IntegratorOptions::fixed(m, 1e-3, 1.0)
                            .with_treatment(ConstraintTreatment::Projection { tolerance: 1e-10 });
                        // Steps limited only by the tolerance (dense output gives the samples).
                        o.max_step = f64::INFINITY;
                        g.push((kind, format!("{f}/dopri5/projection"), o, tol));
                    }
                }
                IntegratorKind::GeneralizedAlpha => {
                    for &h in &a.steps {
                        let o = IntegratorOptions::fixed(Method::GeneralizedAlpha { rho_inf: 0.8 }, h, 1.0);
                        g.push((kind, format!("{f}/generalized-alpha"), o, h));
                    }
                }
                IntegratorKind::Rk4 | IntegratorKind::SymplecticEuler => {
                    let m = if integ == IntegratorKind::Rk4 {
                        Method::Rk4
                    } else {
                        Method::SymplecticEuler
                    };
                    for t in &a.treatments {
                        let st = StabilizationKind::parse(t)
                            .ok_or_else(|| unknown_name("treatment", t, StabilizationKind::NAMES))?;
                        for &h in &a.steps {
                            let treatment = match st {
                                StabilizationKind::None => ConstraintTreatment::None,
                                StabilizationKind::Baumgarte => ConstraintTreatment::baumgarte_for_step(h),
                                StabilizationKind::Projection => ConstraintTreatment::Projection { tolerance: 1e-10 },
                            };
                            let o = IntegratorOptions::fixed(m, h, 1.0).with_treatment(treatment);
                            g.push((kind, format!("{f}/{}/{t}", m.name()), o, h));
                        }
                    }
                }
            }
        }
    }
    Ok(g)
}

pub fn run(a: Args) -> Result<(), String> {
    for (values, flag) in [(&a.steps, "--steps"), (&a.tolerances, "--tolerances")] {
        if let Some(v) = values.iter().find(|v| !(v.is_finite() && **v > 0.0)) {
            return Err(format!("{flag}: every value must be positive and finite, got {v}"));
        }
    }
    let scene = Scene::from_path(&a.scene).map_err(|e| e.to_string())?;
    let end = a.end.unwrap_or(scene.settings.end.min(5.0));
    let largest_step = a.steps.iter().cloned().fold(0.0f64, f64::max);
    let every = a.every.unwrap_or(scene.settings.output_every.max(largest_step));
    if !(end > 0.0 && every > 0.0) {
        return Err("--end and --every must be positive".into());
    }
    let with_every = |mut o: IntegratorOptions| {
        o.output_every = every;
        if o.max_step.is_finite() {
            o.max_step = every;
        }
        o
    };
    // Reference: Dormand–Prince at rtol = atol = 1e-12 with projection, augmented.
    let ref_opts = with_every(
        IntegratorOptions::fixed(
            Method::DormandPrince {
                rtol: 1e-12,
                atol: 1e-12,
            },
            1e-4,
            1.0,
        )
        .with_treatment(ConstraintTreatment::Projection { tolerance: 1e-12 }),
    );
    let (reference, status) = samples(&scene, FormulationKind::Augmented, ref_opts, end);
    status.map_err(|e| format!("reference run failed: {e}"))?;
    outln!(
        "scene        {} ({} s, compared every {} s against dopri5 at rtol 1e-12)",
        scene.name,
        end,
        every
    );
    let g = grid(&a)?;
    let mut runs = Vec::new();
    for (k, (kind, label, opts, parameter)) in g.into_iter().enumerate() {
        let (got, res) = samples(&scene, kind, with_every(opts), end);
        let run = match res {
            Ok((time_s, evaluations, constraint, energy)) => {
                let error = got
                    .iter()
                    .zip(&reference)
                    .flat_map(|(a, b)| a.iter().zip(b).map(|(x, y)| (x - y).abs()))
                    .fold(0.0f64, f64::max);
                Run {
                    method: label,
                    parameter,
                    time_s,
                    evaluations,
                    error: Some(error),
                    constraint,
                    energy,
                    status: "ok".into(),
                }
            }
            Err(e) => Run {
                method: label,
                parameter,
                time_s: f64::NAN,
                evaluations: 0,
                error: None,
                constraint: f64::NAN,
                energy: f64::NAN,
                status: e.replace(',', ";"),
            },
        };
        if std::io::IsTerminal::is_terminal(&std::io::stderr()) {
            eprint!("\r{} runs", k + 1);
        }
        runs.push(run);
    }
    eprintln!();
    std::fs::create_dir_all(&a.output).map_err(|e| format!("{}: {e}", a.output.display()))?;
    write_csv(&a.output.join("trade.csv"), &runs)?;
    let front = pareto(&runs);
    write_markdown(&a.output.join("trade.md"), &scene.name, end, &runs, &front)?;
    plot(&a.output.join("work-precision.svg"), &scene.name, &runs, &front)?;
    outln!("\nbest method per accuracy band (fastest run whose error is within the band):");
    for band in [1e-2, 1e-4, 1e-6, 1e-8, 1e-10] {
        let best = runs
            .iter()
            .filter(|r| r.error.is_some_and(|e| e <= band))
            .min_by(|x, y| x.time_s.total_cmp(&y.time_s));
        match best {
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
    Ok(())
}

/// Indices of the runs on the Pareto front (no other run both faster and more accurate).
fn pareto(runs: &[Run]) -> Vec<usize> {
    let mut ok: Vec<usize> = (0..runs.len()).filter(|&i| runs[i].error.is_some()).collect();
    ok.sort_by(|&a, &b| runs[a].time_s.total_cmp(&runs[b].time_s));
    let mut front = Vec::new();
    let mut best = f64::INFINITY;
    for i in ok {
        let e = runs[i].error.unwrap_or(f64::INFINITY);
        if e < best {
            best = e;
            front.push(i);
        }
    }
    front
}

fn write_csv(path: &std::path::Path, runs: &[Run]) -> Result<(), String> {
    let mut s =
        String::from("method,parameter,time_s,evaluations,error,max_constraint_violation,max_energy_change,status\n");
    for r in runs {
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{}",
            r.method,
            r.parameter,
            r.time_s,
            r.evaluations,
            r.error.map_or("".into(), |e| e.to_string()),
            r.constraint,
            r.energy,
            r.status
        );
    }
    std::fs::write(path, s).map_err(|e| format!("{}: {e}", path.display()))
}

fn write_markdown(path: &std::path::Path, name: &str, end: f64, runs: &[Run], front: &[usize]) -> Result<(), String> {
    let mut s = format!(
        "# Speed–accuracy trade: {name}\n\n{end} s of simulation; error = largest deviation of any coordinate or velocity from a Dormand–Prince run at rtol = atol = 1e-12, at every comparison time. ★ = on the Pareto front.\n\n| method | h or tol | time [ms] | evaluations | error | max \\|C\\| | max \\|ΔE\\| [J] |\n|---|---|---|---|---|---|---|\n"
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

fn plot(path: &std::path::Path, name: &str, runs: &[Run], front: &[usize]) -> Result<(), String> {
    let ok: Vec<&Run> = runs
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
