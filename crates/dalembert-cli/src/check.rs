//! `dalembert check`: prints [`dalembert::Scene::check`].

use dalembert::output::fixed;
use dalembert::scene::{RunOverrides, Spelling};
use dalembert::CheckReport;
use std::path::PathBuf;

/// Arguments of `check`.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML).
    scene: PathBuf,
    /// Redundant constraints: error | minimum-norm (overrides the scene's `redundant`)
    #[arg(long)]
    redundant: Option<String>,
}

pub fn run(a: Args) -> Result<(), String> {
    let mut scene = crate::paths::load_scene(&a.scene)?;
    if a.redundant.is_some() {
        let o = RunOverrides {
            redundant: a.redundant.clone(),
            ..RunOverrides::default()
        };
        let (settings, warnings) = o.apply(&scene.settings, Spelling::Flags)?;
        for w in warnings {
            eprintln!("warning: {w}");
        }
        scene.settings = settings;
    }
    let r = scene.check().map_err(|e| e.to_string())?;
    outln!("scene        {}", r.scene);
    outln!(
        "model        {} bodies, {} coordinates, {} constraint equations (rank {}), {} degree(s) of freedom",
        r.bodies,
        r.coordinates,
        r.equations,
        r.rank,
        r.degrees_of_freedom
    );
    if !r.redundant.is_empty() {
        let treated = if r.minimum_norm {
            " (minimum-norm treatment)"
        } else {
            ""
        };
        outln!("redundant    {}{treated}", r.redundant.join(", "));
    }
    if !scene.inputs.is_empty() {
        outln!(
            "inputs       {} (held at the value last set; 0 until set, and in a run from start to end)",
            scene.inputs.join(", ")
        );
    }
    outln!("assembled    largest |C| = {:.2e}", r.max_violation);
    if let Ok(qdd) = &r.accelerations {
        if scene.model.is_spatial() {
            print_spatial(&r, qdd);
        } else {
            print_planar(&r, qdd);
        }
    }
    let problems = r.problems();
    if problems.is_empty() {
        outln!("\nok");
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}

/// The accelerations and reactions of a planar scene: `ẍ, ÿ, θ̈` per body; `fx, fy` and the torque
/// or effort per joint or driver.
fn print_planar(r: &CheckReport, qdd: &[f64]) {
    outln!("\ninitial accelerations (t = 0)");
    outln!(
        "{:>16} {:>14} {:>14} {:>14}",
        "body",
        "ẍ [m/s²]",
        "ÿ [m/s²]",
        "θ̈ [rad/s²]"
    );
    for (i, chunk) in qdd.chunks(3).enumerate() {
        outln!(
            "{:>16} {} {} {}",
            body_of(&r.coordinate_names[3 * i]),
            fixed(chunk[0], 14, 6),
            fixed(chunk[1], 14, 6),
            fixed(chunk[2], 14, 6)
        );
    }
    outln!("\ninitial reactions (on the first body from the second, global)");
    outln!(
        "{:>16} {:>14} {:>14} {:>14}",
        "joint / driver",
        "fx [N]",
        "fy [N]",
        "torque / effort"
    );
    for (name, fields) in grouped(&r.reactions) {
        let value = |f: &str| fields.iter().find(|(n, _)| *n == f).map(|&(_, v)| v);
        if let Some(e) = value("effort") {
            outln!("{:>16} {:>14} {:>14} {}", name, "", "", fixed(e, 14, 6));
            continue;
        }
        let (Some(fx), Some(fy)) = (value("fx"), value("fy")) else {
            // A rigid contact's gap, normal force and friction, a limit's coordinate and force:
            // each by its name.
            out!("{name:>16}");
            for (field, v) in &fields {
                out!("  {field} {}", fixed(*v, 0, 6));
            }
            outln!();
            continue;
        };
        let t = value("torque").map(|t| fixed(t, 14, 6)).unwrap_or_default();
        outln!("{:>16} {} {} {:>14}", name, fixed(fx, 14, 6), fixed(fy, 14, 6), t);
    }
}

/// The accelerations and reactions of a spatial scene: `r̈` (global) and `ω̇'` (body frame) per
/// body; force and moment (about the joint's point, global) per joint, effort per driver.
fn print_spatial(r: &CheckReport, qdd: &[f64]) {
    outln!("\ninitial accelerations (t = 0; r̈ global [m/s²], ω̇' body frame [rad/s²])");
    outln!(
        "{:>16} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}",
        "body",
        "ẍ",
        "ÿ",
        "z̈",
        "ω̇x'",
        "ω̇y'",
        "ω̇z'"
    );
    for (i, a) in qdd.chunks(6).enumerate() {
        out!("{:>16}", body_of(&r.coordinate_names[6 * i]));
        for x in a {
            out!(" {}", fixed(*x, 11, 5));
        }
        outln!();
    }
    outln!("\ninitial reactions (on the first body from the second, global; moment about the joint's point)");
    outln!(
        "{:>16} {:>11} {:>11} {:>11} {:>11} {:>11} {:>11}",
        "joint / driver",
        "fx [N]",
        "fy [N]",
        "fz [N]",
        "mx [N·m]",
        "my [N·m]",
        "mz [N·m]"
    );
    for (name, fields) in grouped(&r.reactions) {
        out!("{name:>16}");
        if let [("effort", e)] = fields.as_slice() {
            outln!(" effort {}", fixed(*e, 0, 6));
            continue;
        }
        for (_, v) in &fields {
            out!(" {}", fixed(*v, 11, 5));
        }
        outln!();
    }
}

/// The body of a coordinate name `body.label`.
fn body_of(coordinate: &str) -> &str {
    coordinate.rsplit_once('.').map_or(coordinate, |(b, _)| b)
}

/// Reaction columns `name.field` grouped by name, in order: `(name, [(field, value)])`.
fn grouped(columns: &[(String, f64)]) -> Vec<(&str, Vec<(&str, f64)>)> {
    let mut out: Vec<(&str, Vec<(&str, f64)>)> = Vec::new();
    for (column, v) in columns {
        let (name, field) = column.rsplit_once('.').unwrap_or((column, ""));
        match out.last_mut() {
            Some((last, fields)) if *last == name => fields.push((field, *v)),
            _ => out.push((name, vec![(field, *v)])),
        }
    }
    out
}
