//! `dalembert equilibrium` and `dalembert modes`: [`dalembert::Scene::equilibrium`] and
//! [`dalembert::Scene::modes`] printed.

use dalembert::output::shortest;
use dalembert::{Equilibrium, Scene};
use std::path::PathBuf;

/// Arguments of `equilibrium` and `modes`.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML).
    scene: PathBuf,
}

/// Arguments of `equilibrium`.
#[derive(clap::Args)]
pub struct EquilibriumArgs {
    #[command(flatten)]
    scene: Args,
    /// Write the scene started at rest at the equilibrium (its text with an `[initial]` table of
    /// positions and zero velocities). Paths in the scene (a URDF it names) stay relative to it.
    #[arg(long)]
    output: Option<PathBuf>,
}

/// Arguments of `modes`.
#[derive(clap::Args)]
pub struct ModesArgs {
    #[command(flatten)]
    scene: Args,
    /// Write an HTML page animating mode K (1 = the lowest), as `animate` draws a run.
    #[arg(long, value_name = "K")]
    animate: Option<usize>,
    /// Periods of the mode the page plays.
    #[arg(long, default_value_t = 3)]
    cycles: usize,
    /// The page to write (default: the scene's file name with `-mode-K.html`).
    #[arg(long)]
    output: Option<PathBuf>,
}

fn load(a: &Args) -> Result<Scene, String> {
    crate::paths::load_scene(&a.scene)
}

/// `name = value` pairs on one line.
fn pairs(list: &[(String, f64)]) -> String {
    list.iter()
        .map(|(n, v)| format!("{n} = {}", shortest(*v)))
        .collect::<Vec<_>>()
        .join(", ")
}

fn print_equilibrium(scene: &Scene, eq: &Equilibrium) {
    outln!("scene        {}", scene.name);
    let verdict = if eq.stable {
        "stable".to_string()
    } else if !eq.unstable_directions.is_empty() {
        format!("unstable along {}", eq.unstable_directions.join("; "))
    } else {
        format!("neutral along {}", eq.free_directions.join("; "))
    };
    let stiffness = if eq.stiffness.is_empty() {
        "no free motion".to_string()
    } else {
        let values: Vec<String> = eq.stiffness.iter().map(|x| shortest(*x)).collect();
        format!("reduced stiffness over mass: {} 1/s²", values.join(", "))
    };
    outln!(
        "equilibrium  found in {} Newton iteration(s); {verdict} ({stiffness})",
        eq.iterations,
    );
    if !eq.held.is_empty() {
        outln!(
            "held         at a bound of the limits of '{}' (their stops' forces: the .limit columns)",
            eq.held.join("', '")
        );
    }
    outln!("positions    {}", pairs(&eq.positions));
    if !eq.reactions.is_empty() {
        outln!("reactions    {}", pairs(&eq.reactions));
    }
}

/// `dalembert equilibrium SCENE [--output eq.toml]`.
pub fn equilibrium(e: EquilibriumArgs) -> Result<(), String> {
    let scene = load(&e.scene)?;
    let eq = scene.equilibrium().map_err(|e| e.to_string())?;
    print_equilibrium(&scene, &eq);
    if let Some(path) = &e.output {
        let resting = scene.resting_at(&eq).map_err(|e| e.to_string())?;
        std::fs::write(path, &resting.source).map_err(|e| format!("{}: {e}", path.display()))?;
        outln!("written      {} (the scene at rest there)", path.display());
    }
    Ok(())
}

/// `dalembert modes SCENE [--animate K]`.
pub fn modes(m: ModesArgs) -> Result<(), String> {
    let a = &m.scene;
    let scene = load(a)?;
    let modes = scene.modes().map_err(|e| e.to_string())?;
    print_equilibrium(&scene, &modes.equilibrium);
    outln!("\nmode  frequency (Hz)  damping ratio  shape (largest position changes)");
    for (k, ((f, z), shape)) in modes
        .frequencies
        .iter()
        .zip(&modes.damping_ratios)
        .zip(&modes.shapes)
        .enumerate()
    {
        outln!(
            "{:>4}  {:>14}  {:>13}  {}",
            k + 1,
            format!("{f:.6}"),
            format!("{z:.6}"),
            dalembert::equilibrium::describe(&modes.columns, shape)
        );
    }
    if let Some(k) = m.animate {
        if k == 0 || k > modes.frequencies.len() {
            return Err(format!(
                "--animate {k}: the scene has {} mode(s), numbered from 1",
                modes.frequencies.len()
            ));
        }
        let frames = scene.mode_frames(&modes, k - 1, m.cycles).map_err(|e| e.to_string())?;
        let output = m.output.clone().unwrap_or_else(|| {
            let stem = a
                .scene
                .file_stem()
                .map_or("scene".into(), |s| s.to_string_lossy().into_owned());
            PathBuf::from(format!("{stem}-mode-{k}.html"))
        });
        let title = format!("{}: mode {k} at {:.6} Hz", scene.name, modes.frequencies[k - 1]);
        let page = dalembert::animation::Viewer::new(&title, &scene.drawing).html(&frames);
        std::fs::write(&output, page).map_err(|e| format!("{}: {e}", output.display()))?;
        outln!(
            "\nwrote {} (mode {k}, {} frames over {} period(s))",
            output.display(),
            frames.len(),
            m.cycles.max(1)
        );
    }
    Ok(())
}
