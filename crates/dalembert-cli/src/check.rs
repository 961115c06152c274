//! `dalembert check`.

use dalembert::constraints::{ConstraintRole, Reaction, RedundancyTreatment, Stabilization};
use dalembert::Scene;
use std::path::Path;

pub fn run(path: &Path) -> Result<(), String> {
    let scene = Scene::from_path(path).map_err(|e| e.to_string())?;
    let model = scene.model.clone();
    let sys = model.constraints();
    let mut vals = sys.values();
    sys.evaluate(0.0, &scene.q, &scene.qd, &mut vals);
    let s = sys.analyse_structure(&vals, 1e-9).map_err(|e| e.to_string())?;
    outln!("scene        {}", scene.name);
    outln!(
        "model        {} bodies, {} coordinates, {} constraint equations (rank {}), {} degree(s) of freedom",
        model.bodies().len(),
        s.coordinates,
        s.equations,
        s.rank,
        s.degrees_of_freedom
    );
    let mut problems = Vec::new();
    if !s.redundant.is_empty() {
        let list: Vec<String> = s.redundant.iter().map(|e| e.to_string()).collect();
        if scene.settings.redundancy == RedundancyTreatment::MinimumNorm {
            // Asked for: solved on an independent set, reactions by the minimum-norm distribution.
            outln!("redundant    {} (minimum-norm treatment)", list.join(", "));
        } else {
            outln!("redundant    {}", list.join(", "));
            problems.push(format!(
                "{} redundant constraint equation(s): {} (set `redundant = \"minimum-norm\"` in [simulation] or pass --redundant minimum-norm to solve with minimum-norm reactions)",
                s.redundant.len(),
                list.join(", ")
            ));
        }
    }
    let max_c = vals.c.iter().fold(0.0f64, |a, v| a.max(v.abs()));
    outln!("assembled    largest |C| = {max_c:.2e}");
    let mut f = crate::simulate::formulation(&scene)?;
    let (n, m) = (model.num_coordinates(), model.num_equations());
    let (mut qdd, mut lam) = (vec![0.0; n], vec![0.0; m]);
    match f.accelerations(0.0, &scene.q, &scene.qd, Stabilization::None, &mut qdd, &mut lam) {
        Ok(()) => {
            outln!("\ninitial accelerations (t = 0)");
            outln!(
                "{:>16} {:>14} {:>14} {:>14}",
                "body",
                "ẍ [m/s²]",
                "ÿ [m/s²]",
                "θ̈ [rad/s²]"
            );
            for (i, b) in model.bodies().iter().enumerate() {
                outln!(
                    "{:>16} {:14.6} {:14.6} {:14.6}",
                    b.name,
                    qdd[3 * i],
                    qdd[3 * i + 1],
                    qdd[3 * i + 2]
                );
            }
            let mut r = vec![Reaction::default(); sys.constraints().len()];
            sys.reactions(&scene.q, &vals, &lam, &mut r);
            outln!("\ninitial reactions (on the first body from the second, global)");
            outln!(
                "{:>16} {:>14} {:>14} {:>14}",
                "joint / driver",
                "fx [N]",
                "fy [N]",
                "torque / effort"
            );
            for (c, r) in sys.constraints().iter().zip(&r) {
                match c.role() {
                    ConstraintRole::Driver => {
                        outln!(
                            "{:>16} {:>14} {:>14} {:14.6}",
                            c.name(),
                            "",
                            "",
                            r.effort.unwrap_or(f64::NAN)
                        )
                    }
                    ConstraintRole::Joint { carries_torque } => {
                        let t = if carries_torque {
                            format!("{:14.6}", r.torque)
                        } else {
                            String::new()
                        };
                        outln!("{:>16} {:14.6} {:14.6} {:>14}", c.name(), r.force.x, r.force.y, t)
                    }
                }
            }
        }
        Err(e) => problems.push(format!("initial accelerations: {e}")),
    }
    if problems.is_empty() {
        outln!("\nok");
        Ok(())
    } else {
        Err(problems.join("; "))
    }
}
