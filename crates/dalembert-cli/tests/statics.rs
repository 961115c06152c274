//! `dalembert equilibrium` and `dalembert modes` on the command line: the mass on a spring
//! (`tests/data/hanging-spring.toml`) rests at its static deflection and rings at its closed-form
//! frequency and damping ratio, as printed; a scene with no equilibrium exits 1 with one line
//! naming the direction and the force.

mod common;
use common::{dalembert, tmp};

const SPRING: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../tests/data/hanging-spring.toml");

#[test]
fn equilibrium_and_modes_print_the_closed_forms() {
    let (ok, out, err) = dalembert(&["equilibrium", SPRING]);
    assert!(ok, "{err}");
    // y = −1 − m g / k = −1.04905 (printed in shortest round-trip form, to round-off).
    let positions = out.lines().find(|l| l.starts_with("positions")).unwrap();
    let y: f64 = positions
        .split("slider.y = ")
        .nth(1)
        .and_then(|s| s.split(',').next())
        .unwrap()
        .parse()
        .unwrap();
    assert!((y + 1.0 + 2.0 * 9.81 / 400.0).abs() < 1e-12, "{positions}");
    assert!(out.contains("stable"), "{out}");
    let (ok, out, err) = dalembert(&["modes", SPRING]);
    assert!(ok, "{err}");
    // f = √(k/m) / 2π = 2.250791 Hz, ζ = c / (2√(k m)) = 0.070711, printed to 6 decimals.
    let row = out.lines().find(|l| l.trim_start().starts_with("1 ")).unwrap();
    let fields: Vec<&str> = row.split_whitespace().collect();
    assert_eq!(
        fields[1],
        format!("{:.6}", 200f64.sqrt() / (2.0 * std::f64::consts::PI)),
        "{row}"
    );
    assert_eq!(fields[2], format!("{:.6}", 4.0 / (2.0 * 800f64.sqrt())), "{row}");
}

#[test]
fn a_scene_without_equilibrium_exits_1_naming_the_direction() {
    let path = tmp("stone.toml");
    std::fs::write(
        &path,
        "[scene]\ngravity = [0.0, -9.81]\n[[bodies]]\nname = \"stone\"\nmass = 2.0\ninertia = 0.1\nposition = [0.0, 1.0]\n",
    )
    .unwrap();
    let (ok, out, err) = dalembert(&["equilibrium", path.to_str().unwrap()]);
    assert!(!ok && out.is_empty(), "{out}");
    assert_eq!(err.lines().count(), 1, "{err}");
    assert!(
        err.contains("there is none: a net force of 19.62 acts along stone.y"),
        "{err}"
    );
}
