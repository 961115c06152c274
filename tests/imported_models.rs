//! Imported models against the same mechanisms written as scenes (`docs/import.md`): a reader
//! must give the model a scene would, whatever the format. The engines' own checks (Pinocchio,
//! MuJoCo) are the Python tests `test_urdf.py` and `test_mjcf.py`.

use dalembert::output::Table;
use dalembert::{FormulationKind, Scene, SceneValue};
use std::path::Path;
use std::sync::atomic::AtomicBool;

fn data(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/imported")
        .join(name)
}

/// 1 s of `scene` with `formulation`, dopri5 at 1e-11, a row every 0.1 s.
fn run(scene: &Scene, formulation: FormulationKind) -> Table {
    let s = scene
        .with_values(&[
            ("simulation.end", 1.0.into()),
            ("simulation.integrator", "dopri5".into()),
            ("simulation.rtol", 1e-11.into()),
            ("simulation.atol", 1e-12.into()),
            ("simulation.output_every", 0.1.into()),
            ("simulation.formulation", SceneValue::Text(formulation.name().into())),
        ])
        .unwrap();
    let rec = s.record(&AtomicBool::new(false));
    rec.outcome
        .unwrap_or_else(|e| panic!("{} {}: {e}", scene.name, formulation.name()));
    rec.table
}

/// The loop of `loop.xml`, closed by an MJCF `equality connect`, moves as `loop.toml`, the same
/// mechanism written as a scene with a spherical joint: every body's centre of mass and Euler
/// parameters within 1e-9 over 1 s (dopri5 at 1e-11 on both: the gap is the integrator's, the
/// models are equal to round-off), with every formulation; and the mechanism moves (its crank
/// turns more than 0.05 rad).
#[test]
fn an_mjcf_connect_loop_moves_as_the_same_loop_written_as_a_scene() {
    let imported = Scene::from_path(data("loop.xml")).unwrap();
    let written = Scene::from_path(data("loop.toml")).unwrap();
    // The same bodies (the reader lists them as it walks the tree: crank, rocker, coupler).
    let (mut a, mut b) = (imported.model.body_names(), written.model.body_names());
    a.sort();
    b.sort();
    assert_eq!(a, b);
    for f in FormulationKind::ALL {
        let (a, b) = (run(&imported, f), run(&written, f));
        assert_eq!(a.rows(), 11);
        for body in imported.model.body_names() {
            for c in ["x", "y", "z", "e0", "e1", "e2", "e3"] {
                let column = format!("{body}.{c}");
                let (x, y) = (a.column(&column).unwrap(), b.column(&column).unwrap());
                let gap = x.iter().zip(&y).fold(0.0f64, |m, (p, q)| m.max((p - q).abs()));
                assert!(gap < 1e-9, "{} {column}: {gap:.2e}", f.name());
            }
        }
        let crank = a.column("A.q").unwrap();
        assert!(crank.last().unwrap().abs() > 0.05, "the loop moves: crank at {crank:?}");
    }
}
