//! The IFToMM A02 N-four-bar (issue 12): every formulation with the integrators that matter near
//! singular positions, against the exact one-degree-of-freedom reduction
//! (`dalembert_testkit::n_four_bar`). Prints, per setting, the largest error of the point `B₀`
//! over the benchmark's 400 output steps, the wall time, or where and why the run stopped.
//!
//! Run: `cargo run --release --example n_four_bar -- [N] [END]` (defaults 40 and 20 s).

use dalembert::integrators::{IntegratorOptions, Method, Stabilization};
use dalembert::scene::Scene;
use dalembert::simulation::FormulationKind;
use dalembert_testkit::n_four_bar::NFourBar;
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(40);
    let end: f64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(20.0);
    let only: Option<String> = args.next();
    let bar = NFourBar { n };
    let every = end / 400.0;
    let reference = bar.reference(every, end);
    let scene = Scene::from_toml(&bar.toml(end), "n-four-bar")?;
    let projection = Stabilization::Projection { tolerance: 1e-12 };
    let mut settings: Vec<(String, IntegratorOptions)> = [2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4]
        .iter()
        .map(|&h| {
            (
                format!("rk4 + projection, h = {h:e}"),
                IntegratorOptions::fixed(Method::rk4(), h, every).with_stabilization(projection),
            )
        })
        .collect();
    settings.extend([
        (
            "symplectic-euler + projection, h = 1e-4".into(),
            IntegratorOptions::fixed(Method::symplectic_euler(), 1e-4, every).with_stabilization(projection),
        ),
        (
            "dopri5 1e-10 + projection".into(),
            IntegratorOptions::fixed(Method::dopri5(1e-10, 1e-12), 1e-3, every).with_stabilization(projection),
        ),
        (
            "generalized-alpha 0.8, h = 1e-3".into(),
            IntegratorOptions::fixed(Method::generalized_alpha(0.8), 1e-3, every),
        ),
        (
            "generalized-alpha 0.8, h = 1e-4".into(),
            IntegratorOptions::fixed(Method::generalized_alpha(0.8), 1e-4, every),
        ),
    ]);
    settings.extend([1e-2, 5e-3, 2e-3, 1e-3, 5e-4, 2.5e-4, 1e-4].iter().map(|&h| {
        (
            format!("ali3-p, h = {h:e}"),
            IntegratorOptions::fixed(Method::ali3p(0.0), h, every),
        )
    }));
    println!("N-four-bar, N = {n}, {end} s; error = largest |B0 - exact| over 400 output steps");
    for kind in FormulationKind::ALL {
        for (name, options) in &settings {
            if only.as_deref().is_some_and(|o| !name.contains(o)) {
                continue;
            }
            let mut sim = scene.simulation();
            sim.formulation = kind;
            sim.integrator = *options;
            let mut worst = 0.0f64;
            let mut k = 0;
            let start = Instant::now();
            let result = sim.run(&mut |s| {
                if let Some(&(t, th, _)) = reference.get(k) {
                    if (t - s.t).abs() < 1e-9 {
                        worst = worst.max(NFourBar::b0_error(s.q, th));
                        k += 1;
                    }
                }
            });
            let wall = start.elapsed().as_secs_f64();
            match result {
                Ok(s) => println!(
                    "{:>12} {name:<42} error {worst:.1e}  {wall:.2} s  (projection share {:.1e}, energy change {:.1e} J)",
                    kind.name(),
                    s.max_projection_share,
                    s.max_energy_change
                ),
                Err(e) => println!(
                    "{:>12} {name:<42} STOPPED (error so far {worst:.1e}, {wall:.2} s): {}",
                    kind.name(),
                    e.to_string().lines().next().unwrap_or("")
                ),
            }
        }
    }
    Ok(())
}
