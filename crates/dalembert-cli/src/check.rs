//! `dalembert check`: prints [`dalembert::Scene::check`].

use dalembert::Scene;
use std::path::Path;

pub fn run(path: &Path) -> Result<(), String> {
    let scene = Scene::from_path(path).map_err(|e| e.to_string())?;
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
    outln!("assembled    largest |C| = {:.2e}", r.max_violation);
    if let Ok(qdd) = &r.accelerations {
        outln!("\ninitial accelerations (t = 0)");
        outln!(
            "{:>16} {:>14} {:>14} {:>14}",
            "body",
            "ẍ [m/s²]",
            "ÿ [m/s²]",
            "θ̈ [rad/s²]"
        );
        for (i, b) in scene.model.bodies().iter().enumerate() {
            outln!(
                "{:>16} {:14.6} {:14.6} {:14.6}",
                b.name,
                qdd[3 * i],
                qdd[3 * i + 1],
                qdd[3 * i + 2]
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
        // One line per joint or driver: its columns `<name>.fx`, `.fy`, `.torque` / `.effort`.
        let mut k = 0;
        while k < r.reactions.len() {
            let (name, field) = r.reactions[k].0.rsplit_once('.').unwrap_or((&r.reactions[k].0, ""));
            let value = |f: &str| {
                r.reactions[k..]
                    .iter()
                    .take(3)
                    .find(|(n, _)| n.rsplit_once('.') == Some((name, f)))
                    .map(|&(_, v)| v)
            };
            if field == "effort" {
                outln!("{:>16} {:>14} {:>14} {:14.6}", name, "", "", r.reactions[k].1);
                k += 1;
                continue;
            }
            let (fx, fy, torque) = (value("fx"), value("fy"), value("torque"));
            let t = torque.map(|t| format!("{t:14.6}")).unwrap_or_default();
            outln!(
                "{:>16} {:14.6} {:14.6} {:>14}",
                name,
                fx.unwrap_or(f64::NAN),
                fy.unwrap_or(f64::NAN),
                t
            );
            k += 2 + usize::from(torque.is_some());
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
