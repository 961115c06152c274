//! The implicit methods (generalized-α, ALI3-P) on a model with joint limits (`docs/limits.md`,
//! "Refused, and why"): they run while every limit is free and stop where one is reached, naming
//! the joint, with the rows so far kept. A uniform rod (1 kg, 1 m) pinned at its end falls from
//! horizontal: `θ̇² = (3 g / L) sin(−θ)` (energy, `J_O = m L² / 3`), so it reaches `θ = −0.5` at
//!
//! ```text
//! t* = ∫₀^0.5 dφ / √(29.43 sin φ) = ∫₀^√0.5 2u du / √(29.43 sin u²)      (φ = u²)
//! ```
//!
//! (the substitution leaves a smooth integrand: composite Simpson with 2 000 panels, error far
//! below 1e-12 s).

use dalembert::{Scene, SimulationError};
use std::sync::atomic::AtomicBool;

fn rod(limits: [f64; 2], method: &str) -> Scene {
    let toml = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\n[[bodies]]\nname = \"rod\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\n\
         position = [0.5, 0.0]\n\n[[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\n\
         at = [0.0, 0.0]\nlimits = [{}, {}]\n\n[simulation]\nend = 1.0\nstep = 1e-4\nintegrator = \"{method}\"\n",
        limits[0], limits[1]
    );
    Scene::from_toml(&toml, "rod").unwrap()
}

/// `t*`, the time the falling rod reaches −0.5 rad (module documentation).
fn crossing_time() -> f64 {
    let f = |u: f64| 2.0 * u / (29.43 * (u * u).sin()).sqrt();
    let (b, n) = (0.5f64.sqrt(), 2000);
    let h = b / n as f64;
    // f(u) → 2/√29.43 as u → 0.
    let at = |k: usize| if k == 0 { 2.0 / 29.43f64.sqrt() } else { f(k as f64 * h) };
    let inner: f64 = (1..n).map(|k| if k % 2 == 1 { 4.0 * at(k) } else { 2.0 * at(k) }).sum();
    h / 3.0 * (at(0) + inner + at(n))
}

#[test]
fn an_implicit_method_stops_where_the_rod_reaches_its_stop() {
    // Both methods are second order: at h = 1e-4 over 0.26 s the located time is within 1e-6 s of
    // t* (measured 3.3e-9 and 2.6e-9 s). The run stops there with the joint named and the remedy; every row
    // kept is before t*, within the bounds.
    let exact = crossing_time();
    for method in ["generalized-alpha", "ali3-p"] {
        let run = rod([-0.5, 0.5], method).record(&AtomicBool::new(false));
        let Err(SimulationError::Integration(failure)) = &run.outcome else {
            panic!("{method}: {:?}", run.outcome)
        };
        let message = failure.error.to_string();
        assert!(
            message.contains("joint 'pin'") && message.contains("use rk4 or dopri5"),
            "{message}"
        );
        let stopped = failure.error.time().unwrap();
        eprintln!(
            "{method}: stopped at {stopped}, t* = {exact}, off by {:.1e} s",
            stopped - exact
        );
        assert!(
            (stopped - exact).abs() < 1e-6,
            "{method}: stopped at {stopped} for {exact}"
        );
        let (t, q) = (run.table.column("t").unwrap(), run.table.column("pin.q").unwrap());
        assert!(t.len() > 20 && t.iter().all(|t| *t < exact), "{method}");
        assert!(q.iter().all(|q| q.abs() <= 0.5), "{method}");
    }
}

#[test]
fn an_implicit_method_runs_a_model_whose_limits_stay_free() {
    // Limits at −3.5 and 0.5 rad: the rod swings from 0 to −π and back, never reaching them. Generalized-α and
    // ALI3-P at h = 1e-4 agree with the same model without limits run by each to 1e-12 (the limits
    // change nothing while free), and with dopri5 at 1e-12 to 1e-5 rad (second order: about
    // (ω h)² θ over the swing; measured 1.3e-7 and 9.8e-8).
    let angle = |scene: &Scene| scene.record(&AtomicBool::new(false)).table.column("rod.angle").unwrap();
    let reference = {
        let toml = "[scene]\ngravity = [0.0, -9.81]\n\n[[bodies]]\nname = \"rod\"\nmass = 1.0\nshape = { rod = 1.0 }\n\
                    position = [0.5, 0.0]\n\n[[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\n\
                    at = [0.0, 0.0]\n\n[simulation]\nend = 1.0\nintegrator = \"dopri5\"\nrtol = 1e-12\natol = 1e-13\n";
        angle(&Scene::from_toml(toml, "rod").unwrap())
    };
    for method in ["generalized-alpha", "ali3-p"] {
        let limited = rod([-3.5, 0.5], method);
        let free = rod([-1e3, 1e3], method);
        let (a, b) = (angle(&limited), angle(&free));
        assert_eq!(a.len(), reference.len(), "{method}");
        assert!(a.iter().any(|q| *q < -1.5), "{method}: the rod swings down");
        let worst = a.iter().zip(&reference).fold(0.0f64, |w, (x, r)| w.max((x - r).abs()));
        eprintln!("{method}: largest difference from dopri5 {worst:.1e} rad");
        for ((x, y), r) in a.iter().zip(&b).zip(&reference) {
            assert!((x - y).abs() < 1e-12, "{method}: {x} vs {y} without stops");
            assert!((x - r).abs() < 1e-5, "{method}: {x} vs dopri5 {r}");
        }
    }
}
