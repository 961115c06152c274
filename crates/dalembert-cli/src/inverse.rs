//! `dalembert inverse`.

use dalembert::augmented::InverseDynamics;
use dalembert::constraints::KinematicOptions;
use dalembert::integrators::Sample;
use dalembert::{CsvOutput, Scene};
use std::path::PathBuf;

/// Arguments of `inverse`.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML) whose drivers fix every degree of freedom.
    scene: PathBuf,
    /// End time (s); default the scene's.
    #[arg(long)]
    end: Option<f64>,
    /// Output interval (s); default the scene's.
    #[arg(long)]
    every: Option<f64>,
    /// Write efforts and reactions as CSV.
    #[arg(long)]
    output: Option<PathBuf>,
}

pub fn run(a: Args) -> Result<(), String> {
    let scene = Scene::from_path(&a.scene).map_err(|e| e.to_string())?;
    let model = scene.model.clone();
    let end = a.end.unwrap_or(scene.settings.end);
    let every = a.every.unwrap_or(scene.settings.output_every);
    if !(end > 0.0 && every > 0.0) {
        return Err("--end and --every must be positive".into());
    }
    let inv = InverseDynamics::new(model.clone(), &scene.q, KinematicOptions::default()).map_err(|e| e.to_string())?;
    let mut csv = match &a.output {
        Some(p) => {
            let f = std::fs::File::create(p).map_err(|e| format!("{}: {e}", p.display()))?;
            Some(CsvOutput::new(&model, std::io::BufWriter::new(f)).map_err(|e| e.to_string())?)
        }
        None => None,
    };
    let sys = model.constraints();
    let drivers: Vec<usize> = (0..sys.constraints().len())
        .filter(|&k| sys.constraints()[k].role() == dalembert::constraints::ConstraintRole::Driver)
        .collect();
    outln!("scene        {}", scene.name);
    out!("{:>9}", "t [s]");
    for &k in &drivers {
        out!(" {:>16}", format!("{}.effort", sys.constraints()[k].name()));
    }
    outln!();
    let steps = (end / every - 1e-9).ceil() as usize;
    let every_row = (steps / 10).max(1);
    let mut q = scene.q.clone();
    let (mut c, mut cd) = (vec![0.0; model.num_equations()], vec![0.0; model.num_equations()]);
    let mut vals = sys.values();
    for i in 0..=steps {
        let t = (i as f64 * every).min(end);
        let sol = inv.solve(t, &q).map_err(|e| {
            if let Some(c) = csv.take() {
                let _ = c.finish();
            }
            e.to_string()
        })?;
        q.clone_from(&sol.q);
        sys.evaluate(t, &sol.q, &sol.qd, &mut vals);
        c.copy_from_slice(&vals.c);
        sys.velocity_residual(&vals, &sol.qd, &mut cd);
        let energy = model.kinetic_energy(&sol.q, &sol.qd) + model.potential_energy(t, &sol.q);
        let inf = |v: &[f64]| v.iter().fold(0.0f64, |a, x| a.max(x.abs()));
        let sample = Sample {
            t,
            q: &sol.q,
            qd: &sol.qd,
            qdd: &sol.qdd,
            lambda: &sol.lambda,
            constraint_violation: inf(&c),
            velocity_violation: inf(&cd),
            energy,
        };
        if let Some(w) = csv.as_mut() {
            w.write(&model, &sample);
        }
        if i % every_row == 0 || i == steps {
            out!("{t:9.4}");
            for &k in &drivers {
                out!(" {:16.6}", sol.reactions[k].effort.unwrap_or(f64::NAN));
            }
            outln!();
        }
    }
    if let Some(w) = csv {
        w.finish().map_err(|e| format!("writing CSV: {e}"))?;
    }
    Ok(())
}
