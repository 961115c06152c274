//! The augmented formulation's saddle-point back ends on one scene: the time of an RK4 step at
//! 1 ms over 1 s (best of three runs) with each back end, and how far each run's positions end
//! from the automatic choice's (`docs/augmented.md`, the back-end table).
//!
//! ```sh
//! cargo run --release --example backends -- scenes/robots/panda.urdf
//! ```

use dalembert::augmented::{Augmented, AugmentedOptions, Backend};
use dalembert::integrators::{integrate, IntegratorOptions, Method};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let path = std::env::args().nth(1).ok_or("give a scene or a robot description")?;
    let mut sim = dalembert::Scene::from_path(&path)?.simulation();
    sim.assemble()?;
    let sys = sim.model.system();
    let opts = IntegratorOptions::fixed(Method::rk4(), 1e-3, 1.0);
    let mut reference: Option<Vec<f64>> = None;
    for backend in [
        Backend::Auto,
        Backend::Tree,
        Backend::SparseSchur,
        Backend::Schur,
        Backend::Sparse,
        Backend::Dense,
    ] {
        let options = AugmentedOptions {
            backend,
            ..Default::default()
        };
        let mut f = match Augmented::new(sys.clone(), options) {
            Ok(f) => f,
            Err(e) => {
                println!("{backend:?}: {e}");
                continue;
            }
        };
        let (mut best, mut last) = (f64::INFINITY, Vec::new());
        for _ in 0..3 {
            let start = Instant::now();
            integrate(&mut f, 0.0, 1.0, &sim.q, &sim.qd, &opts, &mut |s| last = s.q.to_vec())?;
            best = best.min(start.elapsed().as_secs_f64());
        }
        let apart = reference.as_ref().map_or(0.0, |r| {
            r.iter().zip(&last).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()))
        });
        println!(
            "{backend:?} ({}): {:.1} µs a step; positions at 1 s {apart:.1e} from Auto's",
            f.backend_name(),
            best * 1e6 / 1000.0
        );
        reference.get_or_insert(last);
    }
    Ok(())
}
