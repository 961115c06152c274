//! `dalembert animate`: a self-contained HTML animation of a scene's motion.

use crate::simulate::{load, RunArgs};
use dalembert::animation::{Frames, MeshSources, Trace, Viewer, DEFAULT_MAX_FRAMES};
use std::path::PathBuf;

/// Arguments of `animate`.
#[derive(clap::Args)]
pub struct Args {
    /// Scene file (TOML, or a URDF robot).
    scene: PathBuf,
    #[command(flatten)]
    run: RunArgs,
    /// Replay a result CSV written by `simulate --output` instead of simulating.
    #[arg(long)]
    from: Option<PathBuf>,
    /// Draw the path of a body point, BODY:X,Y in the body's frame (metres; BODY:X,Y,Z in a
    /// spatial scene); repeatable.
    #[arg(long, value_name = "BODY:X,Y[,Z]")]
    trace: Vec<String>,
    /// Largest number of frames kept in the page (a long run is thinned evenly).
    #[arg(long, default_value_t = DEFAULT_MAX_FRAMES)]
    max_frames: usize,
    /// HTML file to write (default: the scene's file name with `.html`, in the current directory).
    #[arg(long)]
    output: Option<PathBuf>,
    /// Read the meshes a robot file names as `package://NAME/…` inside DIR; repeatable. Without
    /// it, those links are drawn as their boxes of inertia.
    #[arg(long, value_name = "NAME=DIR")]
    package: Vec<String>,
    /// Read meshes from absolute paths and through `..` (a model file you trust): by default only
    /// the scene's folder and the named packages are read.
    #[arg(long)]
    any_mesh_path: bool,
}

pub fn run(a: Args) -> Result<(), String> {
    let scene = load(&a.scene, &a.run)?;
    let traces = a
        .trace
        .iter()
        .map(|t| Trace::parse(t, &scene.drawing).map_err(|e| format!("--{e}")))
        .collect::<Result<Vec<_>, _>>()?;
    if a.max_frames < 2 {
        return Err(format!("--max-frames must be at least 2, got {}", a.max_frames));
    }
    let output = a.output.clone().unwrap_or_else(|| {
        let stem = a.scene.file_stem().map(|s| s.to_string_lossy().into_owned());
        PathBuf::from(format!("{}.html", stem.unwrap_or_else(|| "animation".into())))
    });
    let mut inputs: Vec<&std::path::Path> = vec![&a.scene];
    inputs.extend(a.from.as_deref());
    crate::paths::refuse_overwriting(&output, &inputs)?;
    let mut sources = MeshSources::of_scene(&scene.origin).any_path(a.any_mesh_path);
    for p in &a.package {
        let (name, dir) = p
            .split_once('=')
            .filter(|(n, d)| !n.is_empty() && !d.is_empty())
            .ok_or_else(|| format!("--package '{p}': expected NAME=DIR"))?;
        sources = sources.package(name, dir);
    }
    // Meshes are read before the run: a bad one stops here, not after a long simulation.
    let meshes = match &scene.drawing.spatial {
        Some(spatial) => Some(sources.load(spatial).map_err(|e| e.to_string())?),
        None => None,
    };
    for n in meshes.iter().flat_map(|m| &m.notes) {
        eprintln!("note: {n}");
    }
    let (frames, stopped) = match &a.from {
        Some(csv) => {
            let file = std::fs::File::open(csv).map_err(|e| format!("{}: {e}", csv.display()))?;
            let origin = csv.display().to_string();
            let frames =
                Frames::from_csv(std::io::BufReader::new(file), &scene.drawing, &origin).map_err(|e| e.to_string())?;
            (frames, None)
        }
        None => {
            let mut frames = Frames::for_drawing(&scene.drawing);
            // The joints' reactions drawn as arrows: their columns of each row.
            let mut rows = dalembert::output::Rows::new(&scene.model);
            let wanted = Frames::reaction_columns(&scene.drawing);
            let mut forces: Vec<usize> = (wanted.iter())
                .filter_map(|n| rows.names().iter().position(|c| c == n))
                .collect();
            if forces.len() != wanted.len() {
                forces.clear();
            }
            let (mut row, mut f) = (Vec::new(), Vec::new());
            let result = scene.simulation().run_cancellable(
                &mut |s| {
                    frames.push(s.t, s.q);
                    if !forces.is_empty() {
                        row.clear();
                        rows.push(s, &mut row);
                        f.clear();
                        f.extend(forces.iter().map(|&k| row[k]));
                        frames.push_reactions(&f);
                    }
                },
                crate::interrupt_flag(),
            );
            (frames, result.err().map(|e| e.to_string()))
        }
    };
    let mut viewer = Viewer::new(&scene.name, &scene.drawing).max_frames(a.max_frames);
    if let Some(meshes) = meshes {
        viewer = viewer.meshes(meshes);
    }
    for t in traces {
        viewer = viewer.trace(t);
    }
    if let Some(why) = &stopped {
        let at = frames.times.last().map_or(String::new(), |&t| {
            format!(" at t = {} s", dalembert::output::shortest(t))
        });
        viewer = viewer.note(format!("the run stopped{at}: {why}"));
    }
    std::fs::write(&output, viewer.html(&frames)).map_err(|e| format!("{}: {e}", output.display()))?;
    let kept = frames.len().min(a.max_frames);
    outln!(
        "wrote {} ({} frames, t = {} … {} s)",
        output.display(),
        kept,
        dalembert::output::shortest(frames.times.first().copied().unwrap_or(0.0)),
        dalembert::output::shortest(frames.times.last().copied().unwrap_or(0.0))
    );
    match stopped {
        // The page holds every frame computed before the failure; the error says where it stopped.
        Some(why) => Err(why),
        None => Ok(()),
    }
}
