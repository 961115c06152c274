//! `dalembert simulate`.

use crate::method_args::MethodParams;
use dalembert::energy::EnergyBalance;
use dalembert::integrators::Sample;
use dalembert::integrators::StepControl;
use dalembert::output::fixed;
use dalembert::scene::{RunOverrides, Spelling};
use dalembert::{CsvOutput, Scene, SensitivityRequest};
use std::io::{IsTerminal, Write};
use std::path::PathBuf;
use std::time::Instant;

/// Arguments of `simulate`; flags override the scene's `[simulation]` table.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML).
    scene: PathBuf,
    #[command(flatten)]
    run: RunArgs,
    /// Write the results as CSV (streamed: rows before a failure are kept).
    #[arg(long)]
    output: Option<PathBuf>,
    /// Fail (exit 1) instead of warning when a conservative model's energy changes by more than
    /// 1 % of its energy scale.
    #[arg(long)]
    strict: bool,
    /// Sensitivities to these scene values (comma-separated paths, e.g.
    /// forces.spring.stiffness,bodies.upper.mass): the CSV gets columns d(COLUMN)/d(PATH), carried
    /// along with the run by the same method and steps (docs/sensitivities.md)
    #[arg(long, value_delimiter = ',')]
    sensitivities: Vec<String>,
    /// The columns whose sensitivities are written (comma-separated; default: every column but t)
    #[arg(long = "sensitivity-of", value_delimiter = ',', requires = "sensitivities")]
    sensitivity_of: Vec<String>,
    /// Each parameter is changed by ± this share of its value (default 1e-4)
    #[arg(long, allow_hyphen_values = true, requires = "sensitivities")]
    relative_change: Option<f64>,
}

/// Flags that override a scene's `[simulation]` table (`simulate`, `animate`). Numbers may be
/// negative on the command line (`--step -1e-3`), so that the rule rejecting them is the one that
/// speaks.
#[derive(clap::Args)]
pub struct RunArgs {
    /// augmented | embedding | amalgamated
    #[arg(long)]
    formulation: Option<String>,
    /// symplectic-euler | rk4 | dopri5 | generalized-alpha | ali3-p
    #[arg(long)]
    integrator: Option<String>,
    /// The methods' parameters (`--rtol`, `--atol`, `--rho-inf`), from the integrators' registry.
    #[command(flatten)]
    parameters: MethodParams,
    /// Fixed step, or initial step of an adaptive method (s).
    #[arg(long, allow_hyphen_values = true)]
    step: Option<f64>,
    /// End time (s).
    #[arg(long, allow_hyphen_values = true)]
    end: Option<f64>,
    /// Output interval (s).
    #[arg(long, allow_hyphen_values = true)]
    every: Option<f64>,
    /// none | baumgarte | projection
    #[arg(long)]
    stabilization: Option<String>,
    /// Redundant constraints: error | minimum-norm (solve on an independent set; minimum-norm
    /// reactions)
    #[arg(long)]
    redundant: Option<String>,
    /// Coordinates integrated: absolute | joint (a spatial tree of revolute and prismatic joints in
    /// joint coordinates, solved by the articulated-body algorithm; outputs are the same columns)
    #[arg(long)]
    coordinates: Option<String>,
}

/// Loads the scene and applies the command-line overrides (warnings printed).
pub fn load(path: &std::path::Path, a: &RunArgs) -> Result<Scene, String> {
    let mut scene = crate::paths::load_scene(path)?;
    let o = RunOverrides {
        formulation: a.formulation.clone(),
        integrator: a.integrator.clone(),
        parameters: a.parameters.0.clone(),
        step: a.step,
        end: a.end,
        every: a.every,
        stabilization: a.stabilization.clone(),
        redundant: a.redundant.clone(),
        coordinates: a.coordinates.clone(),
    };
    let (settings, warnings) = o.apply(&scene.settings, Spelling::Flags)?;
    for w in warnings {
        eprintln!("warning: {w}");
    }
    scene.settings = settings;
    scene.check_settings(Spelling::Flags)?;
    if let Some(w) = long_run_warning(&scene) {
        eprintln!("warning: {w}");
    }
    Ok(scene)
}

/// Steps past which a fixed-step run gets a warning with its estimated wall time.
const MANY_STEPS: f64 = 1e7;

/// For a fixed-step run of more than [`MANY_STEPS`] steps: the count and the wall time it will
/// take, estimated from 200 steps timed here (a step of 1e-12 s over 5 s is 5e12 steps, hours of
/// work, which a user should hear of before waiting).
fn long_run_warning(scene: &Scene) -> Option<String> {
    let s = &scene.settings;
    if s.method.entry().control == StepControl::Adaptive {
        return None;
    }
    let steps = s.end / s.step;
    if steps.is_nan() || steps <= MANY_STEPS {
        return None;
    }
    let mut probe = scene.simulation();
    probe.end = 200.0 * s.step;
    probe.integrator.output_every = probe.end;
    let per_step = probe.run(&mut |_| {}).ok()?.wall_time.as_secs_f64() / 200.0;
    let seconds = per_step * steps;
    let took = match seconds {
        x if x < 120.0 => format!("{x:.0} s"),
        x if x < 7200.0 => format!("{:.0} min", x / 60.0),
        x if x < 2.0 * 86400.0 => format!("{:.0} h", x / 3600.0),
        x if x < 2.0 * 365.25 * 86400.0 => format!("{:.0} days", x / 86400.0),
        x => format!("{} years", short(x / (365.25 * 86400.0))),
    };
    Some(format!(
        "a step of {} s over {} s is {} steps, about {took} at the {} µs per step measured here; Ctrl-C stops the run keeping the rows so far",
        short(s.step),
        short(s.end),
        short(steps.round()),
        dalembert::output::shortest((per_step * 1e6 * 100.0).round() / 100.0)
    ))
}

pub fn run(a: Args) -> Result<(), String> {
    if let Some(p) = &a.output {
        crate::paths::refuse_overwriting(p, &[&a.scene])?;
    }
    let scene = load(&a.scene, &a.run)?;
    let sim = scene.simulation();
    let mechanism = scene.model.clone();
    let model = mechanism.as_system();
    let s = &scene.settings;
    let dof = scene.structure().map_err(|e| e.to_string())?.degrees_of_freedom;
    let m = &s.method;
    let method = match m.entry().control {
        StepControl::Adaptive => format!("{m}, initial step {} s", short(s.step)),
        _ => format!("{m}, step {}", fixed_step(s)),
    };
    outln!("scene        {}", scene.name);
    outln!(
        "model        {} bodies, {} coordinates, {} constraint equations, {} degree(s) of freedom",
        mechanism.num_bodies(),
        mechanism.num_velocities(),
        model.num_equations(),
        dof
    );
    if s.coordinates == dalembert::Coordinates::Joint {
        // One coordinate per joint, no constraint equations: the three formulations are one
        // equation, solved by the articulated-body algorithm; the joints hold by construction.
        outln!(
            "method       joint coordinates ({} joints, articulated-body algorithm), {}; outputs mapped to the absolute coordinates",
            mechanism.num_bodies(),
            method
        );
    } else {
        outln!(
            "method       {} formulation, {}, constraints: {}",
            s.formulation.name(),
            method,
            if m.entry().keeps_constraints {
                "kept by the method (positions exact to its Newton tolerance)"
            } else {
                s.stabilization.name()
            }
        );
    }
    // Sensitivities are set up (every parameter's scene built and assembled) before the CSV is
    // opened, so that a refused request leaves no file.
    let setup = match a.sensitivities.is_empty() {
        true => None,
        false => {
            let mut request = SensitivityRequest::new(&[], &[]);
            request.parameters = a.sensitivities.clone();
            request.of = a.sensitivity_of.clone();
            if let Some(r) = a.relative_change {
                request.relative_change = r;
            }
            let setup = scene.sensitivity_setup(&request).map_err(|e| e.to_string())?;
            outln!(
                "sensitivity  to {} ({} columns d(…)/d(…), each parameter changed by ±{} of its value)",
                a.sensitivities.join(", "),
                setup.columns.names().len(),
                request.relative_change
            );
            Some(setup)
        }
    };
    let extra: Vec<String> = setup.as_ref().map_or(Vec::new(), |s| s.columns.names().to_vec());
    let mut csv = match &a.output {
        Some(p) => {
            let f = std::fs::File::create(p).map_err(|e| format!("{}: {e}", p.display()))?;
            Some(
                CsvOutput::with_columns(&mechanism, &extra, std::io::BufWriter::new(f))
                    .map_err(|e| format!("{}: {e}", p.display()))?,
            )
        }
        None => None,
    };
    // A few rows for the screen: about ten evenly spaced samples.
    let every_row = (s.end / s.output_every / 10.0).ceil().max(1.0) as u64;
    let mut rows: Vec<Row> = Vec::new();
    let mut k = 0u64;
    let start = Instant::now();
    let tty = std::io::stderr().is_terminal();
    let mut last_bar = Instant::now();
    let end = s.end;
    let summary = mechanism.summary_coordinates(0.0, &scene.q);
    // A model that is not conservative: E − W, the energy less the work of its non-conservative
    // forces and drivers, is what the exact motion keeps (docs/energy.md).
    let mut balance = (!model.is_conservative()).then(|| EnergyBalance::new(model));
    let mut observer = |smp: &Sample<'_>, sensitivities: &[f64]| {
        let e_minus_w = balance.as_mut().map(|b| b.push(model, smp));
        if let Some(c) = csv.as_mut() {
            c.write_with(smp, sensitivities);
        }
        if k.is_multiple_of(every_row) || (smp.t - end).abs() < 1e-12 {
            let angles = summary.iter().take(6).map(|&(_, k)| smp.q[k]).collect();
            rows.push((smp.t, angles, smp.energy, e_minus_w, smp.constraint_violation));
        }
        k += 1;
        if tty && start.elapsed().as_secs_f64() > 1.0 && last_bar.elapsed().as_millis() > 200 {
            last_bar = Instant::now();
            let frac = (smp.t / end).clamp(0.0, 1.0);
            let filled = (frac * 40.0) as usize;
            eprint!(
                "\r[{}{}] {:5.1}%  t = {:.3} s",
                "#".repeat(filled),
                ".".repeat(40 - filled),
                100.0 * frac,
                smp.t
            );
            let _ = std::io::stderr().flush();
        }
    };
    let result = match setup {
        None => sim.run_cancellable(&mut |smp| observer(smp, &[]), crate::interrupt_flag()),
        Some(setup) => scene.run_sensitivities(setup, &mut observer, crate::interrupt_flag()),
    };
    if tty && start.elapsed().as_secs_f64() > 1.0 {
        eprintln!();
    }
    print_rows(&summary, &rows);
    let stats = match result {
        Ok(stats) => stats,
        Err(e) => {
            // Every row computed so far is in the file, which stays well-formed.
            let kept = match (csv, &a.output) {
                (Some(c), Some(p)) => {
                    let (rows, last) = (c.rows(), c.last_time());
                    match c.finish() {
                        Ok(_) => match last {
                            Some(t) => format!(
                                "; {} holds the {rows} rows up to t = {}",
                                p.display(),
                                dalembert::output::shortest(t)
                            ),
                            None => format!("; {} holds the header only: no row was computed", p.display()),
                        },
                        Err(w) => format!("; writing {} also failed: {w}", p.display()),
                    }
                }
                _ => String::new(),
            };
            let advice = scene.advice(&e).map_or(String::new(), |a| format!("; {a}"));
            return Err(format!("{e}{advice}{kept}"));
        }
    };
    if let Some(c) = csv {
        let p = a.output.as_ref().map(|p| p.display().to_string()).unwrap_or_default();
        c.finish().map_err(|e| format!("{p}: {e}"))?;
        outln!(
            "output       {}",
            a.output.as_ref().map(|p| p.display().to_string()).unwrap_or_default()
        );
    }
    outln!(
        "statistics   {} steps ({} rejected), {} evaluations, {} factorizations, {} Newton iterations, {} re-partitions{}{}{}{}",
        stats.steps, stats.rejected, stats.evaluations, stats.factorizations, stats.newton_iterations, stats.repartitions,
        match stats.handovers {
            0 => String::new(),
            k => format!(", {k} projections handed over to the mass-orthogonal one at singular positions"),
        },
        match stats.kicks_undone {
            0 => String::new(),
            k => format!(", {k} kicks of the energy at singular positions undone"),
        },
        match stats.bridges {
            0 => String::new(),
            k => format!(", {k} singular positions bridged with checked steps (accurate to about 31 × the tolerances there)"),
        },
        match stats.events {
            0 => String::new(),
            k => format!(", {k} steps ended at an event (a contact, a stick or slip, an impact)"),
        }
    );
    if stats.tangents_carried + stats.tangents_differenced > 0 {
        outln!(
            "tangents     {} steps carried through the method's stages, {} taken again on the changed models (docs/sensitivities.md)",
            stats.tangents_carried,
            stats.tangents_differenced
        );
    }
    outln!(
        "time         {:.3} ms in the integration loop ({:.2} µs per step)",
        stats.wall_time.as_secs_f64() * 1e3,
        stats.wall_time.as_secs_f64() * 1e6 / stats.steps.max(1) as f64
    );
    let scale = stats.energy_scale;
    match &balance {
        None => outln!(
            "accuracy     largest |C| = {:.2e}, largest |Ċ| = {:.2e}, largest energy change = {:.2e} J (a conservative model: it should be 0)",
            stats.max_constraint_violation,
            stats.max_velocity_violation,
            stats.max_energy_change
        ),
        Some(b) => {
            outln!(
                "accuracy     largest |C| = {:.2e}, largest |Ċ| = {:.2e}, largest energy change = {:.2e} J",
                stats.max_constraint_violation,
                stats.max_velocity_violation,
                stats.max_energy_change
            );
            outln!(
                "energy       not conservative: its forces and drivers did {:.4e} J of work ({}); the energy balance E − W stays within {:.2e} J of its start ({:.1e} of the energy scale {:.3e} J)",
                b.work(),
                non_conservative(&scene),
                b.largest_drift(),
                b.largest_drift() / scale.max(f64::MIN_POSITIVE),
                scale
            );
        }
    }
    let change = match &balance {
        None => stats.max_energy_change,
        Some(b) => b.largest_drift(),
    };
    if let Some(w) = dalembert::energy_warning(change, scale, balance.is_some()) {
        if a.strict {
            return Err(w);
        }
        eprintln!("warning: {w}");
    }
    Ok(())
}

/// The fixed step as run: a whole number of steps spans each output interval, so a step that does
/// not divide the interval (or is longer than it) is shortened, and the summary says so.
fn fixed_step(s: &dalembert::scene::RunSettings) -> String {
    let span = s.output_every.min(s.end);
    let taken = span / (span / s.step - 1e-9).ceil().max(1.0);
    if (taken - s.step).abs() <= 1e-9 * s.step {
        return format!("{} s", short(s.step));
    }
    format!(
        "{} s (asked {} s: a whole number of steps spans each output interval of {} s)",
        short(taken),
        short(s.step),
        short(s.output_every)
    )
}

/// `x` in scientific notation with at most 10 significant digits and no trailing zeros
/// (`1e-3`, `2.5e-3`, never `1.0000000000000002e-3`).
pub fn short(x: f64) -> String {
    let text = format!("{x:.9e}");
    match text.split_once('e') {
        Some((mantissa, exp)) if mantissa.contains('.') => {
            format!("{}e{exp}", mantissa.trim_end_matches('0').trim_end_matches('.'))
        }
        _ => text,
    }
}

/// A printed row: time, summary coordinates, energy, `E − W` (models that are not
/// conservative) and `|C|`.
type Row = (f64, Vec<f64>, f64, Option<f64>, f64);

/// Prints the sampled rows: up to six summary coordinates (`Mechanism::summary_coordinates`),
/// energy, the energy balance `E − W` where the model is not conservative, and `|C|`.
fn print_rows(summary: &[(String, usize)], rows: &[Row]) {
    let names: Vec<&String> = summary.iter().take(6).map(|(n, _)| n).collect();
    let balance = rows.first().is_some_and(|r| r.3.is_some());
    out!("\n{:>9}", "t [s]");
    for n in &names {
        out!(" {:>14}", truncate(n, 14));
    }
    out!(" {:>15}", "energy E [J]");
    if balance {
        out!(" {:>15}", "E − W [J]");
    }
    outln!(" {:>10}", "|C|");
    for (t, angles, e, ew, c) in rows {
        out!("{}", fixed(*t, 9, 4));
        for a in angles.iter().take(6) {
            out!(" {}", fixed(*a, 14, 6));
        }
        out!(" {}", fixed(*e, 15, 8));
        if let Some(ew) = ew {
            out!(" {}", fixed(*ew, 15, 8));
        }
        outln!(" {c:10.2e}");
    }
    outln!();
}

/// What does work in `scene` besides its potential, in words: `force 'motor', force
/// 'return-spring' (damper), driver 'crank'`.
fn non_conservative(scene: &Scene) -> String {
    let items = scene.nonconservative_elements();
    if items.is_empty() {
        "the work of its elements".to_string()
    } else {
        items.join(", ")
    }
}

fn truncate(s: &str, n: usize) -> String {
    if s.chars().count() <= n {
        s.to_string()
    } else {
        s.chars().take(n - 1).collect::<String>() + "…"
    }
}

#[cfg(test)]
mod tests {
    use super::short;

    #[test]
    fn steps_print_short() {
        assert_eq!(short(1.0000000000000002e-3), "1e-3");
        assert_eq!(short(0.01 / 4.0), "2.5e-3");
        assert_eq!(short(5.0), "5e0");
        assert_eq!(short(1.0 / 3.0), "3.333333333e-1");
    }
}
