//! How long loading a robot description takes: read, translate, build and assemble
//! (`docs/import.md`, "Measured").
//!
//! ```sh
//! cargo run --release --example urdf_load -- scenes/robots/ur5.urdf scenes/robots/kinova.urdf
//! ```

use dalembert::Scene;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let paths: Vec<String> = std::env::args().skip(1).collect();
    if paths.is_empty() {
        return Err("give one or more URDF files (or scenes naming one)".into());
    }
    for path in &paths {
        let mut times = Vec::new();
        let mut bodies = 0;
        for _ in 0..200 {
            let start = Instant::now();
            let scene = Scene::from_path(path)?;
            times.push(start.elapsed().as_secs_f64());
            bodies = scene.model.num_bodies();
        }
        times.sort_by(f64::total_cmp);
        println!(
            "{path}: {bodies} bodies, load median {:.2} ms (fastest {:.2} ms, slowest {:.2} ms) over {} loads",
            1e3 * times[times.len() / 2],
            1e3 * times[0],
            1e3 * times[times.len() - 1],
            times.len()
        );
    }
    Ok(())
}
