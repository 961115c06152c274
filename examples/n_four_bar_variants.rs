//! The IFToMM A02 N-four-bar written ten ways (`NFourBar::variant`: bodies and joints shuffled,
//! joints by global or local points, the start moved by 1e-12, end times 20 and 21 s), each run
//! with every formulation at the settings docs/stability.md names: the largest `B₀` error against
//! the exact one-degree-of-freedom reduction over all variants, or where a variant stopped.
//!
//! Then, for comparison, the same count of models whose link lengths are moved by up to 1e-12
//! (`NFourBar::with_lengths_moved`): another mechanism, off the change point, whose exact motion
//! leaves the reduction at the first flat position; their error is printed, not judged.
//!
//! Run: `cargo run --release --example n_four_bar_variants -- [N] [VARIANTS] [ALI3-P STEP] [each|all]
//! [RK4 STEP]` (defaults 2, 10, 1e-3 s, all and 1e-3 s; `each` prints every variant's error).

use dalembert::integrators::{IntegratorOptions, Method, Stabilization};
use dalembert::scene::Scene;
use dalembert::simulation::FormulationKind;
use dalembert_testkit::n_four_bar::{NFourBar, Variant};
use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(2);
    let count: u64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(10);
    let ali3p_step: f64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(1e-3);
    let per_variant = args.next().is_some_and(|a| a == "each");
    let rk4_step: f64 = args.next().map(|a| a.parse()).transpose()?.unwrap_or(1e-3);
    let bar = NFourBar { n };
    let every = 0.05;
    let projection = Stabilization::Projection { tolerance: 1e-12 };
    let ali3p_name = format!("ali3-p, h = {ali3p_step:e}");
    let rk4_name = format!("rk4 + projection, h = {rk4_step:e}");
    let settings: Vec<(&str, IntegratorOptions, bool)> = vec![
        (
            &rk4_name,
            IntegratorOptions::fixed(Method::rk4(), rk4_step, every).with_stabilization(projection),
            false,
        ),
        (
            &ali3p_name,
            IntegratorOptions::fixed(Method::ali3p(0.0), ali3p_step, every),
            true,
        ),
    ];
    println!("N-four-bar, N = {n}, {count} variants; error = largest |B0 - exact| over the outputs");
    let end_of = |seed: u64| if seed.is_multiple_of(2) { 20.0 } else { 21.0 };
    let families: [(&str, &dyn Fn(u64) -> Variant); 2] = [
        ("the benchmark written other ways", &|seed| {
            bar.variant(end_of(seed), seed)
        }),
        (
            "link lengths moved by up to 1e-12 (another mechanism: not judged)",
            &|seed| bar.with_lengths_moved(end_of(seed), seed),
        ),
    ];
    for (family, make) in families {
        println!("{family}:");
        for (name, options, augmented_only) in &settings {
            for kind in FormulationKind::ALL {
                if *augmented_only && kind != FormulationKind::Augmented {
                    continue;
                }
                let (mut worst, mut stops, start) = (0.0f64, Vec::new(), Instant::now());
                for seed in 0..count {
                    let end = end_of(seed);
                    let v = make(seed);
                    let reference = bar.reference_from(v.start, every, end);
                    let scene = Scene::from_toml(&v.toml, "variant")?;
                    let mut sim = scene.simulation();
                    sim.formulation = kind;
                    sim.integrator = *options;
                    let mut k = 0;
                    let mut this = 0.0f64;
                    let result = sim.run(&mut |s| {
                        this = this.max(NFourBar::b0_error(&s.q[3 * v.first_crank..], reference[k].1));
                        k += 1;
                    });
                    worst = worst.max(this);
                    if per_variant {
                        println!("    {seed} {this:.1e} {}", v.description);
                    }
                    if let Err(e) = result {
                        stops.push(format!(
                            "{seed}: {}",
                            e.to_string().chars().take(90).collect::<String>()
                        ));
                    }
                }
                println!(
                    "{:>12} {name:<28} worst {worst:.1e} ({:.2} s){}",
                    kind.name(),
                    start.elapsed().as_secs_f64(),
                    if stops.is_empty() {
                        String::new()
                    } else {
                        format!("; stopped: {}", stops.join(" | "))
                    }
                );
            }
        }
    }
    Ok(())
}
