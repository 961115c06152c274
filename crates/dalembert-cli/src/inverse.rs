//! `dalembert inverse`: [`dalembert::Scene::inverse`] printed and written as CSV.

use dalembert::output::{fixed, Rows};
use dalembert::CsvOutput;
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
    let scene = crate::paths::load_scene(&a.scene)?;
    let model = scene.model.clone();
    let end = a.end.unwrap_or(scene.settings.end);
    let every = a.every.unwrap_or(scene.settings.output_every);
    if !(end > 0.0 && every > 0.0) {
        return Err("--end and --every must be positive".into());
    }
    let mut csv = match &a.output {
        Some(p) => {
            crate::paths::refuse_overwriting(p, &[&a.scene])?;
            let f = std::fs::File::create(p).map_err(|e| format!("{}: {e}", p.display()))?;
            Some(CsvOutput::new(&model, std::io::BufWriter::new(f)).map_err(|e| format!("{}: {e}", p.display()))?)
        }
        None => None,
    };
    let drivers = scene.drivers();
    let mut rows = Rows::new(&model);
    let effort_cols: Vec<usize> = drivers
        .iter()
        .filter_map(|d| rows.names().iter().position(|n| *n == format!("{d}.effort")))
        .collect();
    let steps = (end / every - 1e-9).ceil() as usize;
    let every_row = (steps / 10).max(1);
    let mut i = 0;
    let mut row = Vec::new();
    let res = scene.inverse(end, every, &mut |s| {
        // The header with the first row: a scene the inverse dynamics refuses prints only its error.
        if i == 0 {
            outln!("scene        {}", scene.name);
            out!("{:>9}", "t [s]");
            for d in &drivers {
                out!(" {:>16}", format!("{d}.effort"));
            }
            outln!();
        }
        if let Some(w) = csv.as_mut() {
            w.write(s);
        }
        if i % every_row == 0 || i == steps {
            row.clear();
            rows.push(s, &mut row);
            out!("{}", fixed(s.t, 9, 4));
            for &k in &effort_cols {
                out!(" {}", fixed(row[k], 16, 6));
            }
            outln!();
        }
        i += 1;
    });
    let finished = csv.map(|w| w.finish());
    res.map_err(|e| e.to_string())?;
    if let (Some(Err(e)), Some(p)) = (finished, &a.output) {
        return Err(format!("{}: {e}", p.display()));
    }
    Ok(())
}
