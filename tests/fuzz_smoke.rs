//! Fuzzing on the stable toolchain: structure-aware mutants of the shipped scenes and of the
//! bad-input suite go through the scene loader, and mutants of a result CSV through the reader of
//! `plot` and `animate`. Invariants: no panic, and every error is one line.
//!
//! CI runs a short round. The long run recorded in `docs/robustness.md`:
//!
//! ```sh
//! DALEMBERT_FUZZ_RUNS=1000000 cargo test --release --test fuzz_smoke -- --nocapture
//! ```
//!
//! (`DALEMBERT_FUZZ_SEED` changes the mutation sequence.) A panicking input is written to
//! `target/fuzz-crashes/` and named in the failure.

use dalembert::animation::Frames;
use dalembert::output::read_columns;
use dalembert::{CsvOutput, Scene};
use dalembert_testkit::fuzz::{mutate, Rng};
use std::panic::{catch_unwind, AssertUnwindSafe};
use std::path::{Path, PathBuf};
use std::time::Instant;

fn env_u64(name: &str, default: u64) -> u64 {
    std::env::var(name).ok().and_then(|v| v.parse().ok()).unwrap_or(default)
}

fn texts(dir: &Path) -> Vec<String> {
    texts_of(dir, "toml")
}

/// The text of every file in `dir` whose name ends `.extension`.
fn texts_of(dir: &Path, extension: &str) -> Vec<String> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == extension))
        .collect();
    paths.sort();
    paths
        .iter()
        .map(|p| String::from_utf8_lossy(&std::fs::read(p).unwrap()).into_owned())
        .collect()
}

#[derive(Default, Debug)]
struct Tally {
    runs: u64,
    accepted: u64,
    rejected: u64,
    crashes: Vec<PathBuf>,
    /// Errors that were not one line, with their input.
    multiline: Vec<(String, String)>,
}

/// Runs `target` on `runs` mutants of `seeds` (a quarter of them mutants of the previous mutant).
fn fuzz(name: &str, seeds: &[String], runs: u64, seed: u64, target: &dyn Fn(&str) -> Result<(), String>) -> Tally {
    let mut rng = Rng::new(seed);
    let mut tally = Tally::default();
    let crash_dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("target/fuzz-crashes");
    let hook = std::panic::take_hook();
    std::panic::set_hook(Box::new(|_| {}));
    let start = Instant::now();
    let mut current = rng.pick(seeds).clone();
    for i in 0..runs {
        if rng.below(4) != 0 {
            current = rng.pick(seeds).clone();
        }
        current = mutate(&mut rng, seeds, &current);
        tally.runs += 1;
        match catch_unwind(AssertUnwindSafe(|| target(&current))) {
            Ok(Ok(())) => tally.accepted += 1,
            Ok(Err(message)) => {
                tally.rejected += 1;
                if (message.contains('\n') || message.is_empty()) && tally.multiline.len() < 5 {
                    tally.multiline.push((message, current.clone()));
                }
            }
            Err(_) => {
                std::fs::create_dir_all(&crash_dir).unwrap();
                let path = crash_dir.join(format!("{name}-{seed}-{i}.txt"));
                std::fs::write(&path, &current).unwrap();
                tally.crashes.push(path);
                current = rng.pick(seeds).clone();
            }
        }
    }
    std::panic::set_hook(hook);
    eprintln!(
        "{name}: {} executions in {:.1} s ({:.0}/s): {} accepted, {} rejected with a one-line error, {} panics",
        tally.runs,
        start.elapsed().as_secs_f64(),
        tally.runs as f64 / start.elapsed().as_secs_f64(),
        tally.accepted,
        tally.rejected,
        tally.crashes.len()
    );
    tally
}

#[test]
fn scene_loader_never_panics() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut seeds = texts(&root.join("scenes"));
    seeds.extend(texts(&root.join("tests/bad_inputs")));
    let runs = env_u64("DALEMBERT_FUZZ_RUNS", 20_000);
    let tally = fuzz("scene", &seeds, runs, env_u64("DALEMBERT_FUZZ_SEED", 1), &|text| {
        Scene::from_toml(text, "fuzz.toml")
            .map(|_| ())
            .map_err(|e| e.to_string())
    });
    assert!(tally.crashes.is_empty(), "panics on: {:?}", tally.crashes);
    assert!(
        tally.multiline.is_empty(),
        "errors not on one line: {:#?}",
        tally.multiline
    );
    // The mutants exercise both paths: some still load, most are refused.
    assert!(tally.accepted > runs / 100 && tally.rejected > runs / 4, "{tally:?}");
}

/// Fuzzes a model-file reader on the files under `folders` (relative to the package root) whose
/// names end `.extension`: no panic, every error one line, some mutants accepted.
fn fuzz_reader(
    name: &str,
    folders: &[&str],
    extension: &str,
    load: &dyn Fn(&str) -> Result<Scene, dalembert::SceneError>,
) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let seeds: Vec<String> = folders
        .iter()
        .flat_map(|f| texts_of(&root.join(f), extension))
        .collect();
    let runs = env_u64("DALEMBERT_FUZZ_RUNS", 20_000);
    let tally = fuzz(name, &seeds, runs, env_u64("DALEMBERT_FUZZ_SEED", 1), &|text| {
        load(text).map(|_| ()).map_err(|e| e.to_string())
    });
    assert!(tally.crashes.is_empty(), "panics on: {:?}", tally.crashes);
    assert!(
        tally.multiline.is_empty(),
        "errors not on one line: {:#?}",
        tally.multiline
    );
    assert!(tally.accepted > runs / 100 && tally.rejected > runs / 4, "{tally:?}");
}

#[test]
fn urdf_reader_never_panics() {
    let folders = ["scenes/robots", "tests/bad_inputs", "tests/bad_inputs/models"];
    fuzz_reader("urdf", &folders, "urdf", &|text| Scene::from_urdf(text, "fuzz.urdf"));
}

#[test]
fn mjcf_reader_never_panics() {
    let folders = [
        "scenes/mjcf",
        "tests/bad_inputs",
        "tests/data/imported",
        "tests/data/menagerie/kuka_iiwa_14",
        "tests/data/menagerie/kinova_gen3",
        "tests/data/meshes",
    ];
    fuzz_reader("mjcf", &folders, "xml", &|text| Scene::from_mjcf(text, "fuzz.xml"));
}

#[test]
fn result_csv_reader_never_panics() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let scene = Scene::from_path(root.join("scenes/four-bar.toml")).unwrap();
    let mut sim = scene.simulation();
    sim.end = 0.05;
    let mut csv = CsvOutput::new(&scene.model, Vec::new()).unwrap();
    sim.run(&mut |s| csv.write(s)).unwrap();
    let text = String::from_utf8(csv.finish().unwrap()).unwrap();
    let quoted = text.replacen("crank.x", "\"crank,\"\"x\"\"\"", 1);
    let seeds = vec![text, quoted];
    let names: Vec<String> = ["crank.x", "coupler.angle", "D.fy", "energy"]
        .map(String::from)
        .to_vec();
    let runs = env_u64("DALEMBERT_FUZZ_RUNS", 20_000);
    let tally = fuzz("csv", &seeds, runs, env_u64("DALEMBERT_FUZZ_SEED", 1), &|text| {
        read_columns(text.as_bytes(), "fuzz.csv", &names).map_err(|e| e.to_string())?;
        Frames::from_csv(text.as_bytes(), &scene.drawing, "fuzz.csv").map_err(|e| e.to_string())?;
        Ok(())
    });
    assert!(tally.crashes.is_empty(), "panics on: {:?}", tally.crashes);
    assert!(
        tally.multiline.is_empty(),
        "errors not on one line: {:#?}",
        tally.multiline
    );
    assert!(tally.accepted > runs / 100 && tally.rejected > runs / 10, "{tally:?}");
}
