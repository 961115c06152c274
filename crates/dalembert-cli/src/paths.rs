//! Output files checked against the command's input files before anything is written.

use dalembert::Scene;
use std::path::Path;

/// Loads a scene file (TOML or URDF) and prints what its reader left out of the model
/// ([`Scene::notes`]) as `note:` lines on standard error.
pub fn load_scene(path: impl AsRef<Path>) -> Result<Scene, String> {
    let scene = Scene::from_path(path).map_err(|e| e.to_string())?;
    for n in &scene.notes {
        eprintln!("note: {n}");
    }
    Ok(scene)
}

/// An error when `output` is one of `inputs`, however either is spelled (`./s.toml`, an absolute
/// path, a symbolic or hard link): writing it would destroy the input before it is read, or
/// replace a scene with a CSV.
pub fn refuse_overwriting(output: &Path, inputs: &[&Path]) -> Result<(), String> {
    for input in inputs {
        if same_file(output, input) {
            return Err(format!(
                "{}: the output would overwrite the input {}; choose another output file",
                output.display(),
                input.display()
            ));
        }
    }
    Ok(())
}

/// True when both paths exist and name one file.
fn same_file(a: &Path, b: &Path) -> bool {
    let (Ok(ma), Ok(mb)) = (std::fs::metadata(a), std::fs::metadata(b)) else {
        return false;
    };
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        ma.dev() == mb.dev() && ma.ino() == mb.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (ma, mb);
        matches!((a.canonicalize(), b.canonicalize()), (Ok(x), Ok(y)) if x == y)
    }
}
