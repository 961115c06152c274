//! Coulomb friction in joints, loaded by the joint's reaction (`docs/friction.md`), against
//! numbers from elsewhere: a block on an incline slides at `g (sin α − μ cos α)` when
//! `tan α > μ` and stays at rest when `tan α < μ`; a pendulum with pin friction `μ r |F|` follows
//! its equation of motion integrated independently here (the pin force from Newton's law for
//! the centre of mass); the energy balance closes; every formulation agrees.

mod common;

use common::run;
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
                assert!(
                    error < 1e-12,
                    "{formulation}, {integrator}: t = {}: off by {error:.2e} m",
                    t[k]
                );
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
                assert!(
                    moved < 1e-12,
                    "{formulation}, {integrator}: moved {moved:.2e} m by t = {}",
                    t[k]
                );
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
        assert!(
            balance.abs() < 1e-12 * 19.62,
            "t = {}: E − W moved by {balance:.2e} J",
            t[k]
        );
    }
}

#[test]
fn a_block_pushed_up_an_incline_stops_where_the_closed_form_says_and_stays() {
    // tan 0.5 < μ = 0.6, pushed up the slope at 2 m/s: it decelerates at
    // g (sin α + μ cos α) until it stops at t* = 2 / that (0.2027 s), then stays. The slip's end
    // is an event: the step ends there (dense output or the slip rate's tangent) and the joint
    // sticks. The acceleration is constant on each side, so the methods are exact but for
    // round-off: within 1e-12 m over 2 s, every formulation; one event.
    let (alpha, mu): (f64, f64) = (0.5, 0.6);
    let a = G * (alpha.sin() + mu * alpha.cos());
    let stop = 2.0 / a;
    for formulation in FORMULATIONS {
        for integrator in ["rk4", "dopri5"] {
            let scene = incline(alpha, mu, -2.0, formulation, integrator);
            let rec = scene.record(&AtomicBool::new(false));
            let stats = rec.outcome.unwrap();
            let table = rec.table;
            let t = table.column("t").unwrap();
            for k in 0..t.len() {
                let tt = t[k].min(stop);
                let expected = -(2.0 * tt - 0.5 * a * tt * tt);
                let error = (slid(&table, alpha, k) - expected).abs();
                assert!(
                    error < 1e-12,
                    "{formulation}, {integrator}: t = {}: off by {error:.2e} m",
                    t[k]
                );
            }
            assert_eq!(stats.events, 1, "{formulation}, {integrator}: events");
        }
    }
}

/// A rod of 1 kg and 1 m pinned to the ground at one end (pin radius `r`, friction `mu`),
/// released from the horizontal at rest.
fn pendulum(mu: f64, r: f64, formulation: &str, integrator: &str, end: f64) -> Scene {
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"rod\"\nmass = 1.0\nshape = {{ rod = 1.0 }}\nposition = [0.5, 0.0]\nangle = 0.0\n\
         [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0]\n\
         friction = {{ coefficient = {mu}, radius = {r} }}\n\
         [simulation]\nend = {end}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
         step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n"
    );
    Scene::from_toml(&text, "pendulum").unwrap()
}

/// The rod's angle from its equation of motion about the pin, `J_O φ̈ = −m g d cos φ + T`, with
/// the pin friction `T = −σ μ r |F|` and the pin force `F = m (a_c − g)` from Newton's law for
/// the centre of mass (`a_c` depends on `φ̈`: solved by fixed-point iteration, contraction
/// `μ r m d / J_O`); RK4 at 10 μs, each reversal of the swing located by secant iterations on
/// the step that crosses it. Samples every 0.01 s up to `end`.
fn pendulum_reference(mu: f64, r: f64, end: f64) -> Vec<f64> {
    let (m, d) = (1.0, 0.5);
    let j = m * 1.0 / 3.0;
    let accel = |phi: f64, w: f64, sigma: f64| -> f64 {
        let mut a = -m * G * d * phi.cos() / j;
        for _ in 0..60 {
            let (s, c) = phi.sin_cos();
            let f = [m * d * (-s * a - c * w * w), m * (d * (c * a - s * w * w) + G)];
            a = (-m * G * d * c - sigma * mu * r * (f[0] * f[0] + f[1] * f[1]).sqrt()) / j;
        }
        a
    };
    let rk4 = |(phi, w): (f64, f64), h: f64, sigma: f64| -> (f64, f64) {
        let k1 = (w, accel(phi, w, sigma));
        let k2 = (
            w + 0.5 * h * k1.1,
            accel(phi + 0.5 * h * k1.0, w + 0.5 * h * k1.1, sigma),
        );
        let k3 = (
            w + 0.5 * h * k2.1,
            accel(phi + 0.5 * h * k2.0, w + 0.5 * h * k2.1, sigma),
        );
        let k4 = (w + h * k3.1, accel(phi + h * k3.0, w + h * k3.1, sigma));
        (
            phi + h / 6.0 * (k1.0 + 2.0 * k2.0 + 2.0 * k3.0 + k4.0),
            w + h / 6.0 * (k1.1 + 2.0 * k2.1 + 2.0 * k3.1 + k4.1),
        )
    };
    let h: f64 = 1e-5;
    let mut state = (0.0, 0.0);
    // Released at rest: it falls (φ̇ < 0), the friction opposing.
    let mut sigma = -1.0;
    let mut t = 0.0;
    let mut out = vec![0.0];
    let mut next = 1;
    while next as f64 * 0.01 <= end + 1e-9 {
        let target = next as f64 * 0.01;
        let step = h.min(target - t);
        let mut after = rk4(state, step, sigma);
        let mut taken = step;
        if after.1 * sigma < 0.0 {
            // The swing reverses inside the step: where φ̇ = 0 (secant on the step's size).
            let (mut s0, mut w0, mut s1, mut w1) = (0.0, state.1, step, after.1);
            for _ in 0..30 {
                let s = s1 - w1 * (s1 - s0) / (w1 - w0);
                let w = rk4(state, s, sigma).1;
                (s0, w0, s1, w1) = (s1, w1, s, w);
                if w == 0.0 || (s1 - s0).abs() < 1e-18 {
                    break;
                }
            }
            taken = s1;
            after = (rk4(state, s1, sigma).0, 0.0);
            sigma = -sigma;
        }
        state = after;
        t += taken;
        if (t - target).abs() < 1e-12 {
            t = target;
            out.push(state.0);
            next += 1;
        }
    }
    out
}

#[test]
fn a_pendulum_with_pin_friction_follows_its_equation_of_motion() {
    // μ = 0.2 on a pin of 5 cm: the friction torque μ r |F| (F the pin force, which the swing
    // changes) slows each swing; the gravity torque at each turning point exceeds what the
    // friction can hold, so the swing reverses (three times in 3 s; with the start from rest,
    // four events). Against the independent integration above, every formulation: measured
    // 6.1e-10 rad for dopri5 at 1e-11 and RK4 at 1 ms alike (2026-11-27), the part they share
    // being the reference's own; the bar 1e-8 rad is RK4's (ωh)⁴ error at 1 ms over 3 s with a
    // margin (ω ≈ 3.8 rad/s). A reversal missed or taken at the wrong time is off by 4e-3 rad.
    let (mu, r, end) = (0.2, 0.05, 3.0);
    let reference = pendulum_reference(mu, r, end);
    for formulation in FORMULATIONS {
        for (integrator, bar) in [("dopri5", 1e-8), ("rk4", 1e-8)] {
            let rec = pendulum(mu, r, formulation, integrator, end).record(&AtomicBool::new(false));
            let stats = rec.outcome.unwrap();
            let phi = rec.table.column("rod.angle").unwrap();
            assert_eq!(phi.len(), reference.len());
            let worst = phi
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(worst < bar, "{formulation}, {integrator}: off by {worst:.2e} rad");
            assert_eq!(stats.events, 4, "{formulation}, {integrator}: events");
        }
    }
}

#[test]
fn a_spatial_pendulum_with_pin_friction_follows_the_same_equation_of_motion() {
    // The rod of the test above as a spatial body on a revolute joint about −y (its fall in the
    // x–z plane is a negative angle): the spatial joint's slip row (its value's rate on
    // body-frame angular velocities) and its load (the pin's three force rows; the moment rows
    // hold the axis and do not load the friction), against the same independent integration.
    // The bar is the planar test's, 1e-8 rad.
    // In joint coordinates too (the tree's one coordinate, its load the force the joint
    // transmits by the recursive Newton–Euler pass): the same bar.
    let (mu, r, end) = (0.2, 0.05, 3.0);
    let reference = pendulum_reference(mu, r, end);
    for (formulation, coordinates) in FORMULATIONS.iter().flat_map(|f| [(f, "absolute"), (f, "joint")]) {
        for integrator in ["dopri5", "rk4"] {
            let text = format!(
                "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
                 [[bodies]]\nname = \"rod\"\nmass = 1.0\ninertia = [0.001, 0.08333333333333333, 0.08333333333333333]\n\
                 position = [0.5, 0.0, 0.0]\n\
                 [[joints]]\nname = \"pin\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\n\
                 axis = [0.0, -1.0, 0.0]\nfriction = {{ coefficient = {mu}, radius = {r} }}\n\
                 [simulation]\nend = {end}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
                 step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\ncoordinates = \"{coordinates}\"\n"
            );
            let rec = Scene::from_toml(&text, "spatial pendulum")
                .unwrap()
                .record(&AtomicBool::new(false));
            let stats = rec.outcome.unwrap();
            let angle = rec.table.column("pin.q").unwrap();
            assert_eq!(angle.len(), reference.len());
            let worst = angle
                .iter()
                .zip(&reference)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                worst < 1e-8,
                "{formulation}, {integrator}, {coordinates}: {worst:.2e} rad from the reference"
            );
            assert_eq!(stats.events, 4, "{formulation}, {integrator}, {coordinates}: events");
        }
    }
}

#[test]
fn a_spatial_block_on_an_incline_slides_at_g_sin_minus_mu_cos_and_stays_when_it_can() {
    // A box on a spatial prismatic joint along a slope of α in the x–z plane: the normal load is
    // the guide's two lateral force rows (their norm, m g cos α), the closed forms of the planar
    // tests: s = ½ g (sin α − μ cos α) t² when tan α > μ, at rest when tan α < μ, within 1e-12 m.
    // In joint coordinates too: the load is then the force across the axis that the guide
    // transmits (the recursive Newton–Euler pass), the same bars.
    let alpha: f64 = 0.5;
    let (c, s) = (alpha.cos(), alpha.sin());
    for (mu, a) in [(0.3, G * (s - 0.3 * c)), (0.6, 0.0)] {
        for (formulation, coordinates) in FORMULATIONS.iter().flat_map(|f| [(f, "absolute"), (f, "joint")]) {
            for integrator in ["rk4", "dopri5"] {
                let text = format!(
                    "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
                     [[bodies]]\nname = \"block\"\nmass = 2.0\ninertia = [0.01, 0.02, 0.03]\nposition = [0.0, 0.0, 1.0]\n\
                     [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"block\"]\n\
                     at = [0.0, 0.0, 1.0]\naxis = [{c}, 0.0, {}]\nfriction = {{ coefficient = {mu} }}\n\
                     [simulation]\nend = 2.0\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
                     step = 1e-3\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.05\ncoordinates = \"{coordinates}\"\n",
                    -s
                );
                let table = run(&Scene::from_toml(&text, "spatial incline").unwrap());
                let (t, q) = (table.column("t").unwrap(), table.column("guide.q").unwrap());
                for k in 0..t.len() {
                    let error = (q[k] - 0.5 * a * t[k] * t[k]).abs();
                    assert!(
                        error < 1e-12,
                        "μ = {mu}, {formulation}, {integrator}, {coordinates}: t = {}: off by {error:.2e} m",
                        t[k]
                    );
                }
                // The guide's reaction (what the block exerts on the ground through it) holds
                // the friction too: by Newton's law on the block, m (g − a) with a = a (cos α,
                // 0, −sin α) down the slope (the whole weight when it stays): 1e-9 N of 19.6 N.
                let m = 2.0;
                let expected = [-m * a * c, 0.0, -m * G + m * a * s];
                for (axis, want) in ["fx", "fy", "fz"].into_iter().zip(expected) {
                    let got = *table.column(&format!("guide.{axis}")).unwrap().last().unwrap();
                    assert!(
                        (got - want).abs() < 1e-9,
                        "μ = {mu}, {formulation}, {integrator}, {coordinates}: guide.{axis} = {got}, Newton's law {want}"
                    );
                }
            }
        }
    }
}

/// A slider of 2 kg thrown at 2 m/s along a level guide (`gravity` across it, planar or spatial)
/// with a constant friction of 3 N (`friction = { constant = 3.0 }`): no load-dependent part.
fn thrown_slider(spatial: bool, formulation: &str, integrator: &str) -> Scene {
    let vector = |x: f64| {
        if spatial {
            format!("[{x}, 0.0, 0.0]")
        } else {
            format!("[{x}, 0.0]")
        }
    };
    let (gravity, body) = if spatial {
        ("[0.0, 0.0, -9.81]", "inertia = [0.01, 0.01, 0.01]")
    } else {
        ("[0.0, -9.81]", "shape = { rectangle = [0.2, 0.1] }")
    };
    let text = format!(
        "[scene]\ngravity = {gravity}\n\
         [[bodies]]\nname = \"block\"\nmass = 2.0\n{body}\nposition = {}\nvelocity = {}\n\
         [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"block\"]\n\
         at = {}\naxis = {}\nfriction = {{ constant = 3.0 }}\n\
         [simulation]\nend = 2.0\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
         step = 1e-3\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.05\n",
        vector(0.0),
        vector(2.0),
        vector(0.0),
        vector(1.0),
    );
    Scene::from_toml(&text, "thrown slider").unwrap()
}

#[test]
fn a_constant_friction_stops_a_thrown_slider_where_its_work_takes_the_kinetic_energy() {
    // F₀ = 3 N on 2 kg: the slider decelerates at 1.5 m/s², stops at t* = 4/3 s after
    // v₀²/(2a) = 4/3 m and stays there (the friction holds it with no force: nothing pushes).
    // Constant acceleration: RK4 and dopri5 are exact but for round-off and the event's
    // location (1e-10 m); the friction column is −3 N while it slides. Planar and spatial,
    // every formulation; the energy balance E − W (W = −F₀ x) closes to 1e-9 J.
    let (a, v0) = (1.5, 2.0);
    for spatial in [false, true] {
        for formulation in FORMULATIONS {
            for integrator in ["rk4", "dopri5"] {
                let table = run(&thrown_slider(spatial, formulation, integrator));
                let (t, x) = (table.column("t").unwrap(), table.column("block.x").unwrap());
                let friction = table.column("guide.friction").unwrap();
                let energy = table.column("energy").unwrap();
                for k in 0..t.len() {
                    let s = t[k].min(v0 / a);
                    let expected = v0 * s - 0.5 * a * s * s;
                    let at = format!("spatial {spatial} {formulation} {integrator} t = {}", t[k]);
                    assert!((x[k] - expected).abs() < 1e-10, "{at}: x {} vs {expected}", x[k]);
                    if t[k] < v0 / a - 1e-9 && t[k] > 0.0 {
                        assert!((friction[k] + 3.0).abs() < 1e-9, "{at}: friction {}", friction[k]);
                    }
                    let balance = energy[k] + 3.0 * x[k] - energy[0];
                    assert!(balance.abs() < 1e-9, "{at}: E − W drifts {balance:e} J");
                }
            }
        }
    }
}
