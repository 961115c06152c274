//! Times the static equilibrium of spatial chains of 16 and 64 links started in their file
//! configuration (`dalembert_testkit::spatial::chain3d_toml`: links in a horizontal line, far from
//! rest; equilibrium alone, then equilibrium and modes) and the equilibrium and modes of the
//! chain of 64 started hanging, as
//! `docs/statics.md` reports: `cargo run --release --example statics_chain`.

use std::time::Instant;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    for n in [16, 64] {
        let scene = dalembert::Scene::from_toml(&dalembert_testkit::spatial::chain3d_toml(n, 1.0), "chain")?;
        let start = Instant::now();
        let eq = scene.equilibrium()?;
        let equilibrium = start.elapsed();
        let start = Instant::now();
        let modes = scene.modes()?;
        let with_modes = start.elapsed();
        println!(
            "chain of {n}: equilibrium in {:.1} ms ({} Newton iterations, stable: {}, {} unstable directions); with the modes {:.1} ms, lowest {:.6} Hz",
            equilibrium.as_secs_f64() * 1e3,
            eq.iterations,
            eq.stable,
            eq.unstable_directions.len(),
            with_modes.as_secs_f64() * 1e3,
            modes.frequencies[0]
        );
    }
    // The spatial chain of 64 started hanging (its first joint turned down by `[initial]`): the
    // equilibrium and modes where a user would ask for them.
    let hanging =
        dalembert_testkit::spatial::chain3d_toml(64, 1.0) + "\n[initial]\njoints = { joint0 = 1.5707963267948966 }\n";
    let scene = dalembert::Scene::from_toml(&hanging, "hanging spatial chain")?;
    let start = Instant::now();
    let modes = scene.modes()?;
    println!(
        "spatial chain of 64 hanging: equilibrium and modes in {:.1} ms ({} Newton iterations), lowest {:.6} Hz",
        start.elapsed().as_secs_f64() * 1e3,
        modes.equilibrium.iterations,
        modes.frequencies[0]
    );
    // A planar chain of 64 rods started hanging at rest: the equilibrium and modes of a model of
    // 192 coordinates.
    let scene = dalembert::Scene::from_toml(&hanging_chain(64), "hanging chain")?;
    let start = Instant::now();
    let modes = scene.modes()?;
    println!(
        "planar chain of 64 hanging: equilibrium and modes in {:.1} ms ({} Newton iterations), lowest {:.6} Hz",
        start.elapsed().as_secs_f64() * 1e3,
        modes.equilibrium.iterations,
        modes.frequencies[0]
    );
    // Its linear model about that equilibrium (64 angles and rates: 128 states), with the tip's
    // position as an output.
    for (name, options) in [
        ("at the equilibrium", dalembert::LinearizeOptions::default()),
        (
            "at the initial state",
            dalembert::LinearizeOptions {
                outputs: vec!["link63.x".into(), "link63.y".into()],
                about: dalembert::About::Initial,
                ..Default::default()
            },
        ),
    ] {
        let start = Instant::now();
        let lin = scene.linearize(&options)?;
        println!(
            "planar chain of 64 hanging: linearized {name} in {:.1} ms ({} states)",
            start.elapsed().as_secs_f64() * 1e3,
            lin.states.len()
        );
    }
    Ok(())
}

/// A planar chain of `n` uniform rods (1 kg, 1 m) hanging straight down from the ground.
fn hanging_chain(n: usize) -> String {
    let mut text = String::from("[scene]\ngravity = [0.0, -9.81]\n");
    for k in 0..n {
        let y = -(k as f64) - 0.5;
        text += &format!("[[bodies]]\nname = \"link{k}\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\nposition = [0.0, {y}]\nangle = -1.5707963267948966\n");
        let parent = if k == 0 {
            "ground".to_string()
        } else {
            format!("link{}", k - 1)
        };
        text += &format!(
            "[[joints]]\nname = \"j{k}\"\ntype = \"revolute\"\nbodies = [\"{parent}\", \"link{k}\"]\nat = [0.0, {}]\n",
            -(k as f64)
        );
    }
    text
}
