//! Compliant sphere–plane contact (`docs/contact.md`) against numbers from elsewhere: a ball
//! without dissipation bounces back to the height it fell from and keeps its energy (the contact's
//! potential counted); a dissipative vertical drop against an independent integration of its
//! one-dimensional equation; a ball thrown sliding along the floor decelerates at `μ g` and ends
//! rolling at `5/7` of its speed (angular momentum about the contact line is conserved whatever
//! the friction law); a ball at rest presses into the floor by Hertz's `(m g / k)^(1/n)`.

mod common;

use common::{column, run};
use dalembert::Scene;
use std::sync::atomic::AtomicBool;

const G: f64 = 9.81;
const M: f64 = 1.0;
const R: f64 = 0.1;
const K: f64 = 1e6;

/// A ball of mass `M` and radius `R` at height `z` above the floor (`K`, Hertz's exponent 3/2),
/// RK4 at `step` (`end` and `step` in the second-last pair), output every `every`.
#[allow(clippy::too_many_arguments)]
fn ball(z: f64, v: [f64; 3], w: [f64; 3], dissipation: f64, friction: f64, end: f64, step: f64, every: f64) -> Scene {
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"ball\"\nmass = {M}\nshape = {{ sphere = {R} }}\nposition = [0.0, 0.0, {z}]\n\
         velocity = [{}, {}, {}]\nangular_velocity = [{}, {}, {}]\n\
         [[forces]]\nname = \"floor\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = {R}\n\
         plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\nstiffness = {K}\n\
         dissipation = {dissipation}\nfriction = {friction}\n\
         [simulation]\nend = {end}\nintegrator = \"rk4\"\nstep = {step}\noutput_every = {every}\n",
        v[0], v[1], v[2], w[0], w[1], w[2]
    );
    Scene::from_toml(&text, "ball").unwrap()
}

#[test]
fn a_ball_without_dissipation_bounces_back_to_its_height_and_keeps_its_energy() {
    // Dropped from 1 m (centre), no dissipation, no friction: T + V (gravity and the contact's
    // k δ^{5/2} / (5/2)) stays constant, and after the bounce the ball rises back to 1 m. The
    // force ∝ δ^{3/2} has an unbounded second derivative at touchdown and lift-off, where RK4
    // loses its order inside a step: the energy drift measured 3.8e-5, 2.5e-6, 5.9e-7 J at
    // h = 100, 50, 25 μs before the loop ended steps there (events, on the chord of the gap),
    // 5.4e-6, 1.4e-6, 2.4e-7 J since (what is left is RK4's error inside the 8 ms contact,
    // (ωh)⁴ with ω ≈ 420 rad/s at its deepest). At 25 μs: energy within 1e-6 J (1e-7 of the
    // 9.81 J scale), apex within 1e-7 m (the same energy over m g), the deepest point within
    // 1e-7 m (sampled every 0.1 ms, refined by a parabola: 1e-9).
    let table = run(&ball(1.0, [0.0; 3], [0.0; 3], 0.0, 0.0, 0.9, 2.5e-5, 1e-4));
    let (z, e) = (table.column("ball.z").unwrap(), table.column("energy").unwrap());
    let drift = e.iter().fold(0.0f64, |a, x| a.max((x - e[0]).abs()));
    assert!(drift < 1e-6, "energy changed by {drift:.2e} J");
    // The deepest point: all the energy m g (z₀ − R + δ) in the contact's potential
    // k δ^{5/2} / (5/2) (solved by fixed-point iteration), against the sampled minimum refined by
    // the parabola through its three samples.
    let mut deepest = 0.01;
    for _ in 0..50 {
        deepest = (2.5 * M * G * (1.0 - R + deepest) / K).powf(0.4);
    }
    let k = (1..z.len() - 1).min_by(|&a, &b| z[a].total_cmp(&z[b])).unwrap();
    let (a, b, c) = (z[k - 1], z[k], z[k + 1]);
    let lowest = b - (a - c).powi(2) / (8.0 * (a - 2.0 * b + c));
    assert!(
        (lowest - (R - deepest)).abs() < 1e-7,
        "the ball reached {lowest} m, expected {}",
        R - deepest
    );
    // The bounce ends near t = 2 √(2 (1 − R) / g) = 0.857 s: the apex of the sampled motion
    // after the bounce, refined by the parabola through the three samples around it.
    let k = (1..z.len() - 1)
        .filter(|&i| z[i] >= z[i - 1] && z[i] >= z[i + 1] && i > 1000)
        .max_by(|&a, &b| z[a].total_cmp(&z[b]))
        .unwrap();
    let (a, b, c) = (z[k - 1], z[k], z[k + 1]);
    let apex = b - (a - c).powi(2) / (8.0 * (a - 2.0 * b + c));
    assert!((apex - 1.0).abs() < 1e-7, "apex {apex} m");
}

/// The vertical drop in one dimension, `m z̈ = −m g + k δ^{3/2} (1 + d δ̇)` with `δ = R − z`,
/// integrated here by RK4 at 1 μs: another program for the same law.
fn drop_reference(z0: f64, d: f64, end: f64) -> Vec<(f64, f64)> {
    let accel = |z: f64, v: f64| {
        let depth = R - z;
        let f = if depth > 0.0 {
            (K * depth.powf(1.5) * (1.0 - d * v)).max(0.0)
        } else {
            0.0
        };
        -G + f / M
    };
    let h = 1e-6;
    let (mut z, mut v, mut t) = (z0, 0.0, 0.0);
    let mut out = vec![(t, z)];
    let every = 1000;
    let steps = (end / h).round() as usize;
    for i in 1..=steps {
        let (k1z, k1v) = (v, accel(z, v));
        let (k2z, k2v) = (v + 0.5 * h * k1v, accel(z + 0.5 * h * k1z, v + 0.5 * h * k1v));
        let (k3z, k3v) = (v + 0.5 * h * k2v, accel(z + 0.5 * h * k2z, v + 0.5 * h * k2v));
        let (k4z, k4v) = (v + h * k3v, accel(z + h * k3z, v + h * k3v));
        z += h / 6.0 * (k1z + 2.0 * k2z + 2.0 * k3z + k4z);
        v += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
        t = i as f64 * h;
        if i % every == 0 {
            out.push((t, z));
        }
    }
    out
}

#[test]
fn a_dissipative_drop_follows_its_one_dimensional_equation() {
    // d = 0.2 s/m: the ball leaves the first contact slower and bounces lower each time. The
    // reference integrates the same law by another program at 1 μs; dalembert's RK4 at 25 μs,
    // its steps ended where each contact begins and ends, agrees within 1e-7 m over three bounces
    // (measured 1.3e-8; 8.8e-8 before the steps ended there).
    let reference = drop_reference(0.5, 0.2, 1.2);
    let table = run(&ball(0.5, [0.0; 3], [0.0; 3], 0.2, 0.0, 1.2, 2.5e-5, 1e-3));
    let (t, z) = (table.column("t").unwrap(), table.column("ball.z").unwrap());
    assert_eq!(t.len(), reference.len());
    let worst = (reference.iter().zip(&z)).fold(0.0f64, |a, ((_, zr), z)| a.max((zr - z).abs()));
    let lowest = z.iter().cloned().fold(f64::INFINITY, f64::min);
    let apexes = z.windows(3).filter(|w| w[1] > w[0] && w[1] >= w[2]).count();
    assert!(apexes >= 2, "the run should bounce at least twice, apexes {apexes}");
    assert!(lowest < R, "the ball should touch the floor");
    assert!(worst < 1e-7, "largest difference {worst:.2e} m");
}

#[test]
fn a_ball_thrown_sliding_ends_rolling_at_five_sevenths_of_its_speed() {
    // A solid ball (J = 2/5 m R²) set down on the floor at its resting penetration, sliding at
    // 2 m/s without spin, μ = 0.3. While it slides its centre decelerates at μ g and its spin grows
    // at 5 μ g / (2 R); it rolls from t* = 2 v₀ / (7 μ g) = 0.194 s at v₀ · 5/7 whatever the
    // friction law does at the change (the angular momentum about the contact line is kept).
    // Set down at its resting penetration without vertical speed, it presses with m g exactly, so
    // the sliding phase is Coulomb's exactly: the speed at t*/2 and the rolling speed within
    // 1e-10 m/s (measured 3e-14).
    let depth = (M * G / K).powf(1.0 / 1.5);
    let v0 = 2.0;
    let table = run(&ball(R - depth, [v0, 0.0, 0.0], [0.0; 3], 0.2, 0.3, 0.5, 1e-4, 1e-3));
    let (t, vx, wy) = (
        table.column("t").unwrap(),
        table.column("ball.vx").unwrap(),
        table.column("ball.wy").unwrap(),
    );
    let star = 2.0 * v0 / (7.0 * 0.3 * G);
    let i = t.iter().position(|&s| s >= star / 2.0).unwrap();
    let sliding = v0 - 0.3 * G * t[i];
    assert!(
        (vx[i] - sliding).abs() < 1e-10,
        "at {} s: {} m/s, expected {sliding}",
        t[i],
        vx[i]
    );
    let last = vx.len() - 1;
    assert!((vx[last] - 5.0 / 7.0 * v0).abs() < 1e-10, "rolling at {} m/s", vx[last]);
    // Rolling: the contact point is at rest, v = ω R (ω about y: v_x = ω_y R for a ball rolling
    // along +x).
    assert!(
        (vx[last] - wy[last] * R).abs() < 1e-10,
        "v = {} and ω R = {}",
        vx[last],
        wy[last] * R
    );
}

#[test]
fn a_ball_at_rest_presses_into_the_floor_by_hertz_law() {
    // From 1 mm above its resting height, with dissipation d = 5 s/m, the ball settles at
    // δ = (m g / k)^{2/3} = 4.58e-4 m. About rest it rings at ω = √(1.5 k δ^{1/2} / m) ≈ 180 rad/s
    // with a damping ratio m g d / (2 m ω) ≈ 0.14: after 1 s the 1 mm is below e^{−25} of itself,
    // and the rest within 1e-9 m.
    let depth = (M * G / K).powf(1.0 / 1.5);
    let scene = ball(R - depth + 1e-3, [0.0; 3], [0.0; 3], 5.0, 0.0, 1.0, 1e-4, 1e-3);
    let table = run(&scene);
    let z = table.column("ball.z").unwrap();
    let last = *z.last().unwrap();
    assert!(
        (last - (R - depth)).abs() < 1e-9,
        "rests at {last}, expected {}",
        R - depth
    );
}

/// A planar disk of mass `M` and radius `R` at height `y` above the ground line `y = 0`
/// (`circle-line`, the same law), RK4 at `step`, output every `every`.
#[allow(clippy::too_many_arguments)]
fn disk(y: f64, vx: f64, omega: f64, dissipation: f64, friction: f64, end: f64, step: f64, every: f64) -> Scene {
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"disk\"\nmass = {M}\nshape = {{ disk = {R} }}\nposition = [0.0, {y}]\n\
         velocity = [{vx}, 0.0]\nangular_velocity = {omega}\n\
         [[forces]]\nname = \"ground\"\ntype = \"circle-line\"\nbody = \"disk\"\nradius = {R}\n\
         line = {{ point = [0.0, 0.0], normal = [0.0, 2.0] }}\nstiffness = {K}\n\
         dissipation = {dissipation}\nfriction = {friction}\n\
         [simulation]\nend = {end}\nintegrator = \"rk4\"\nstep = {step}\noutput_every = {every}\n"
    );
    Scene::from_toml(&text, "disk").unwrap()
}

#[test]
fn a_disk_dropped_on_a_line_moves_as_the_ball_on_the_plane() {
    // The planar element and the spatial one are two programs for one law: a disk and a ball of
    // the same mass and radius dropped vertically move alike, bitwise but for the order of
    // floating-point operations: within 1e-12 m over three dissipative bounces.
    let planar = run(&disk(0.5, 0.0, 0.0, 0.2, 0.0, 1.2, 2.5e-5, 1e-3));
    let spatial = run(&ball(0.5, [0.0; 3], [0.0; 3], 0.2, 0.0, 1.2, 2.5e-5, 1e-3));
    let (y, z) = (planar.column("disk.y").unwrap(), spatial.column("ball.z").unwrap());
    assert_eq!(y.len(), z.len());
    let worst = y.iter().zip(&z).fold(0.0f64, |a, (y, z)| a.max((y - z).abs()));
    assert!(worst < 1e-12, "disk and ball differ by {worst:.2e} m");
}

#[test]
fn a_disk_thrown_sliding_ends_rolling_at_two_thirds_of_its_speed() {
    // A uniform disk (J = m R² / 2) sliding at 2 m/s without spin, μ = 0.3: decelerates at μ g,
    // rolls at v₀ / (1 + J / (m R²)) = 2/3 v₀ with v = −ω R (ω counter-clockwise), within 1e-10
    // (it presses with m g exactly, set down at its resting penetration).
    let depth = (M * G / K).powf(1.0 / 1.5);
    let v0 = 2.0;
    let table = run(&disk(R - depth, v0, 0.0, 0.2, 0.3, 0.5, 1e-4, 1e-3));
    let (t, vx, w) = (
        table.column("t").unwrap(),
        table.column("disk.vx").unwrap(),
        table.column("disk.omega").unwrap(),
    );
    let star = v0 / (3.0 * 0.3 * G);
    let i = t.iter().position(|&s| s >= star / 2.0).unwrap();
    assert!(
        (vx[i] - (v0 - 0.3 * G * t[i])).abs() < 1e-10,
        "sliding at {} m/s",
        vx[i]
    );
    let last = vx.len() - 1;
    assert!((vx[last] - 2.0 / 3.0 * v0).abs() < 1e-10, "rolling at {} m/s", vx[last]);
    assert!(
        (vx[last] + w[last] * R).abs() < 1e-10,
        "v = {}, ω R = {}",
        vx[last],
        w[last] * R
    );
}

/// Two balls of mass `M`, radius `R` on the x axis, `a` at 0 moving at `v` toward `b` at `gap`
/// (centre to centre) at rest, without gravity: `sphere-sphere` with dissipation `d`.
fn two_balls(v: f64, gap: f64, d: f64) -> Scene {
    let body = |name: &str, x: f64, vx: f64| {
        format!("[[bodies]]\nname = \"{name}\"\nmass = {M}\nshape = {{ sphere = {R} }}\nposition = [{x}, 0.0, 0.0]\nvelocity = [{vx}, 0.0, 0.0]\n")
    };
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, 0.0]\n{}{}\
         [[forces]]\nname = \"touch\"\ntype = \"sphere-sphere\"\nbodies = [\"a\", \"b\"]\nradii = [{R}, {R}]\n\
         stiffness = {K}\ndissipation = {d}\n\
         [simulation]\nend = 0.3\nintegrator = \"rk4\"\nstep = 2.5e-5\noutput_every = 1e-3\n",
        body("a", 0.0, v),
        body("b", gap, 0.0)
    );
    Scene::from_toml(&text, "two balls").unwrap()
}

#[test]
fn two_equal_balls_exchange_their_velocities_and_keep_momentum() {
    // An elastic central impact of equal masses: momentum and energy conservation leave a at rest
    // and b at the impact speed once they part (the contact lasts about 6 ms at 1 m/s). Momentum
    // is kept to round-off at every sample (the contact forces are internal): 1e-12; the
    // exchanged velocities within 1e-6 m/s (RK4 at 25 μs, the order lost at touchdown).
    let table = run(&two_balls(1.0, 0.25, 0.0));
    let (va, vb) = (table.column("a.vx").unwrap(), table.column("b.vx").unwrap());
    let momentum = va
        .iter()
        .zip(&vb)
        .fold(0.0f64, |m, (a, b)| m.max((M * (a + b) - M).abs()));
    assert!(momentum < 1e-12, "momentum changed by {momentum:.2e}");
    let last = va.len() - 1;
    assert!(
        va[last].abs() < 1e-6 && (vb[last] - 1.0).abs() < 1e-6,
        "a {} b {}",
        va[last],
        vb[last]
    );
}

#[test]
fn a_dissipative_impact_of_two_balls_follows_its_one_dimensional_equation() {
    // With d = 0.5 s/m the balls part slower: their relative motion is the one-dimensional
    // m/2 ẍ = −k δ^{3/2} (1 + d δ̇), δ = 2R − x, integrated here by another program (RK4 at 1 μs),
    // which gives the velocity with which they part: each ball's final speed within 1e-7 m/s of
    // it (and momentum still exact).
    let (v, gap, d) = (1.0, 0.25, 0.5);
    let (mut x, mut xd, h) = (gap, -v, 1e-6);
    let accel = |x: f64, xd: f64| {
        let depth = 2.0 * R - x;
        let f = if depth > 0.0 {
            (K * depth.powf(1.5) * (1.0 - d * xd)).max(0.0)
        } else {
            0.0
        };
        f / (0.5 * M)
    };
    for _ in 0..(0.3 / h) as usize {
        let (k1x, k1v) = (xd, accel(x, xd));
        let (k2x, k2v) = (xd + 0.5 * h * k1v, accel(x + 0.5 * h * k1x, xd + 0.5 * h * k1v));
        let (k3x, k3v) = (xd + 0.5 * h * k2v, accel(x + 0.5 * h * k2x, xd + 0.5 * h * k2v));
        let (k4x, k4v) = (xd + h * k3v, accel(x + h * k3x, xd + h * k3v));
        x += h / 6.0 * (k1x + 2.0 * k2x + 2.0 * k3x + k4x);
        xd += h / 6.0 * (k1v + 2.0 * k2v + 2.0 * k3v + k4v);
    }
    assert!(xd > 0.0 && xd < v, "the reference should part slower: {xd}");
    let table = run(&two_balls(v, gap, d));
    let (va, vb) = (table.column("a.vx").unwrap(), table.column("b.vx").unwrap());
    let last = va.len() - 1;
    // Centre of mass at v/2; relative speed xd.
    let (want_a, want_b) = (0.5 * v - 0.5 * xd, 0.5 * v + 0.5 * xd);
    assert!(
        (va[last] - want_a).abs() < 1e-7 && (vb[last] - want_b).abs() < 1e-7,
        "a {} (want {want_a}), b {} (want {want_b})",
        va[last],
        vb[last]
    );
}

#[test]
fn an_adaptive_method_ends_its_steps_where_a_contact_begins_and_ends() {
    // dopri5 on the elastic drop: each contact's beginning and end are events the loop ends a step
    // at (bisection on the dense output), so the steps grown in the flight neither step over the
    // contact nor carry the force's kink inside a step. One bounce: two events; the energy kept
    // and the apex back at 1 m to the method's tolerance (rtol 1e-10: within 1e-7 J and 1e-8 m;
    // measured 1.8e-8 J and 7.9e-10 m) in 223 steps (bar 400), where RK4 needed 36 000 steps for
    // 6e-7 J.
    // Sampled every 10 ms (the largest step dopri5 takes is the output interval): the flight is a
    // parabola, which the three samples around the apex give exactly.
    let scene = ball(1.0, [0.0; 3], [0.0; 3], 0.0, 0.0, 0.9, 1e-3, 1e-2)
        .with_values(&[
            ("simulation.integrator", "dopri5".into()),
            ("simulation.rtol", 1e-10.into()),
            ("simulation.atol", 1e-12.into()),
        ])
        .unwrap();
    let rec = scene.record(&AtomicBool::new(false));
    let stats = rec.outcome.unwrap();
    let table = rec.table;
    assert_eq!(stats.events, 2, "touchdown and lift-off");
    let (z, e) = (table.column("ball.z").unwrap(), table.column("energy").unwrap());
    let drift = e.iter().fold(0.0f64, |a, x| a.max((x - e[0]).abs()));
    assert!(drift < 1e-7, "energy changed by {drift:.2e} J");
    let k = (1..z.len() - 1)
        .filter(|&i| z[i] >= z[i - 1] && z[i] >= z[i + 1] && i > 10)
        .max_by(|&a, &b| z[a].total_cmp(&z[b]))
        .unwrap();
    let (a, b, c) = (z[k - 1], z[k], z[k + 1]);
    let apex = b - (a - c).powi(2) / (8.0 * (a - 2.0 * b + c));
    assert!((apex - 1.0).abs() < 1e-8, "apex {apex} m");
    assert!(stats.steps < 400, "{} steps", stats.steps);
}

#[test]
fn two_disks_collide_as_two_balls() {
    // circle-circle and sphere-sphere are two programs for one law: two equal disks in the plane
    // and two equal balls in space, the same central impact with dissipation, move alike to
    // within 1e-12 m/s.
    let (v, gap, d) = (1.0, 0.25, 0.5);
    let body = |name: &str, x: f64, vx: f64| {
        format!("[[bodies]]\nname = \"{name}\"\nmass = {M}\nshape = {{ disk = {R} }}\nposition = [{x}, 0.0]\nvelocity = [{vx}, 0.0]\n")
    };
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0]\n{}{}\
         [[forces]]\nname = \"touch\"\ntype = \"circle-circle\"\nbodies = [\"a\", \"b\"]\nradii = [{R}, {R}]\n\
         stiffness = {K}\ndissipation = {d}\n\
         [simulation]\nend = 0.3\nintegrator = \"rk4\"\nstep = 2.5e-5\noutput_every = 1e-3\n",
        body("a", 0.0, v),
        body("b", gap, 0.0)
    );
    let planar = run(&Scene::from_toml(&text, "two disks").unwrap());
    let spatial = run(&two_balls(v, gap, d));
    for (p, s) in [("a.vx", "a.vx"), ("b.vx", "b.vx"), ("b.x", "b.x")] {
        let (x, y) = (planar.column(p).unwrap(), spatial.column(s).unwrap());
        assert_eq!(x.len(), y.len());
        let worst = x.iter().zip(&y).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(worst < 1e-12, "{p}: disks and balls differ by {worst:.2e}");
    }
}

/// A body of 2 kg (inertia `inertia`) at `position`, moving at `v` and `w`, touching a floor
/// through the element `element` (its type and shape keys), `K` with Hertz's exponent 3/2,
/// `dissipation`; dopri5 at 1e-10 to `end`.
fn on_the_floor(
    element: &str,
    inertia: [f64; 3],
    position: [f64; 3],
    vw: ([f64; 3], [f64; 3]),
    dissipation: f64,
    end: f64,
) -> Scene {
    let (v, w) = vw;
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"solid\"\nmass = 2.0\ninertia = {inertia:?}\nposition = {position:?}\n\
         velocity = {v:?}\nangular_velocity = {w:?}\n\
         [[forces]]\nname = \"floor\"\n{element}\nbody = \"solid\"\n\
         plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\nstiffness = {K}\n\
         dissipation = {dissipation}\n\
         [simulation]\nend = {end}\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.01\n"
    );
    Scene::from_toml(&text, "solid on the floor").unwrap()
}

#[test]
fn a_box_and_a_capsule_rest_on_their_corners_and_caps_by_hertz_law() {
    // At rest each contact point carries its share of the weight m g and presses in by Hertz's
    // (F / k)^(1/n): a box flat on a face rests on its four lower corners (m g / 4 each), a
    // capsule lying along the floor on both end caps (m g / 2), one standing on its lower cap
    // (m g). Released touching the floor with dissipation, each settles there: its centre within
    // 1e-9 m of the closed form after 3 s (dopri5 at 1e-10; measured at round-off).
    let (m, n) = (2.0, 1.5);
    let sink = |share: f64| (m * G / share / K).powf(1.0 / n);
    let cases = [
        (
            "box flat",
            "type = \"box-plane\"\nsize = [0.4, 0.3, 0.2]",
            [0.0217, 0.0417, 0.0533],
            0.1,
            0.1 - sink(4.0),
        ),
        (
            "capsule lying",
            "type = \"capsule-plane\"\nradius = 0.05\nat = [[-0.2, 0.0, 0.05], [0.2, 0.0, 0.05]]",
            [0.002, 0.03, 0.03],
            0.05,
            0.05 - sink(2.0),
        ),
        (
            "capsule standing",
            "type = \"capsule-plane\"\nradius = 0.05\nat = [[0.0, 0.0, 0.05], [0.0, 0.0, 0.45]]",
            [0.03, 0.03, 0.002],
            0.25,
            0.25 - sink(1.0),
        ),
    ];
    for (what, element, inertia, z0, expected) in cases {
        let table = run(&on_the_floor(
            element,
            inertia,
            [0.0, 0.0, z0],
            ([0.0; 3], [0.0; 3]),
            5.0,
            3.0,
        ));
        let z = *column(&table, "solid.z").last().unwrap();
        assert!(
            (z - expected).abs() < 1e-9,
            "{what}: rests at z = {z}, expected {expected}"
        );
    }
}

#[test]
fn a_tumbling_box_and_capsule_without_dissipation_keep_their_energy() {
    // Dropped from 0.2–0.25 m onto the floor turning about all three axes, without dissipation or
    // friction: each corner's or cap's force is conservative, with the potential k δⁿ⁺¹/(n + 1)
    // counted in the energy column, so T + V stays at its start through the impacts on one, two
    // or more corners (a conservation law; dopri5 at 1e-10: measured 2.0e-8 and 2.5e-8 J of 6.5 J, bar 1e-6 J).
    let spin = ([0.3, -0.2, 0.0], [4.0, -3.0, 2.0]);
    let cases = [
        (
            "box",
            "type = \"box-plane\"\nsize = [0.4, 0.3, 0.2]",
            [0.0217, 0.0417, 0.0533],
            0.3,
        ),
        (
            "capsule",
            "type = \"capsule-plane\"\nradius = 0.05\nat = [[-0.2, 0.0, 0.3], [0.2, 0.0, 0.3]]",
            [0.002, 0.03, 0.03],
            0.3,
        ),
    ];
    for (what, element, inertia, z0) in cases {
        let table = run(&on_the_floor(element, inertia, [0.0, 0.0, z0], spin, 0.0, 1.5));
        let energy = column(&table, "energy");
        // It bounced: falling at first, rising later.
        let vz = column(&table, "solid.vz");
        assert!(vz[10] < 0.0 && vz.iter().any(|&v| v > 0.5), "{what}: it never bounced");
        let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max);
        assert!(drift < 1e-6, "{what}: the energy moved {drift:e} J from {}", energy[0]);
    }
}

/// A planar body of 2 kg (`shape`) at `position` and `angle`, moving at `v` and `omega`, touching
/// the ground's line y = 0 through the element `element` (its type and shape keys), `K` with
/// Hertz's exponent 3/2, `dissipation`; dopri5 at 1e-10 to `end`.
fn on_the_line(
    element: &str,
    shape: &str,
    position: [f64; 2],
    motion: ([f64; 2], f64),
    dissipation: f64,
    end: f64,
) -> Scene {
    let (v, omega) = motion;
    let text = format!(
        "[scene]\ngravity = [0.0, -9.81]\n\
         [[bodies]]\nname = \"solid\"\nmass = 2.0\nshape = {shape}\nposition = {position:?}\n\
         velocity = {v:?}\nangular_velocity = {omega}\n\
         [[forces]]\nname = \"floor\"\n{element}\nbody = \"solid\"\n\
         line = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}\nstiffness = {K}\ndissipation = {dissipation}\n\
         [simulation]\nend = {end}\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.01\n"
    );
    Scene::from_toml(&text, "solid on the line").unwrap()
}

#[test]
fn a_polygon_and_a_segment_rest_on_their_vertices_and_ends_by_hertz_law() {
    // The planar counterparts of the box and the capsule: a rectangle lying on its long side
    // rests on its two lower vertices (m g / 2 each), a rounded segment lying on both ends
    // (m g / 2), standing on one (m g): each presses in by (F / k)^(2/3), within 1e-9 m after 3 s
    // (measured at round-off).
    let (m, n) = (2.0, 1.5);
    let sink = |share: f64| (m * G / share / K).powf(1.0 / n);
    let rectangle = "type = \"polygon-line\"\nvertices = [[-0.2, 0.0], [0.2, 0.0], [0.2, 0.2], [-0.2, 0.2]]";
    let lying = "type = \"segment-line\"\nradius = 0.05\nat = [[-0.2, 0.05], [0.2, 0.05]]";
    let standing = "type = \"segment-line\"\nradius = 0.05\nat = [[0.0, 0.05], [0.0, 0.45]]";
    let cases = [
        (
            "rectangle",
            rectangle,
            "{ rectangle = [0.4, 0.2] }",
            0.1,
            0.1 - sink(2.0),
        ),
        ("segment lying", lying, "{ rod = 0.5 }", 0.05, 0.05 - sink(2.0)),
        (
            "segment standing",
            standing,
            "{ rectangle = [0.1, 0.5] }",
            0.25,
            0.25 - sink(1.0),
        ),
    ];
    for (what, element, shape, y0, expected) in cases {
        let table = run(&on_the_line(element, shape, [0.0, y0], ([0.0, 0.0], 0.0), 5.0, 3.0));
        let y = *column(&table, "solid.y").last().unwrap();
        assert!(
            (y - expected).abs() < 1e-9,
            "{what}: rests at y = {y}, expected {expected}"
        );
    }
}

#[test]
fn a_tumbling_polygon_and_segment_without_dissipation_keep_their_energy() {
    // Dropped turning onto the line, no dissipation or friction: T + V with every vertex's or
    // end's contact potential stays at its start (a conservation law; measured 3.7e-8 and
    // 5.4e-8 J of 6.3 J, bar 1e-6 J).
    let rectangle = "type = \"polygon-line\"\nvertices = [[-0.2, 0.2], [0.2, 0.2], [0.2, 0.4], [-0.2, 0.4]]";
    let segment = "type = \"segment-line\"\nradius = 0.05\nat = [[-0.2, 0.3], [0.2, 0.3]]";
    for (what, element, shape) in [
        ("rectangle", rectangle, "{ rectangle = [0.4, 0.2] }"),
        ("segment", segment, "{ rod = 0.5 }"),
    ] {
        let table = run(&on_the_line(element, shape, [0.0, 0.3], ([0.3, 0.0], 4.0), 0.0, 1.5));
        let energy = column(&table, "energy");
        let vy = column(&table, "solid.vy");
        assert!(vy[10] < 0.0 && vy.iter().any(|&v| v > 0.5), "{what}: it never bounced");
        let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max);
        assert!(drift < 1e-6, "{what}: the energy moved {drift:e} J from {}", energy[0]);
    }
}

/// A compliant contact's output columns (`<name>.gap`, `.normal`, `.fx` … `.pz`,
/// `docs/contact.md`, "Output") against the statics and the friction law: the ball of
/// [`a_ball_thrown_sliding_ends_rolling_at_five_sevenths_of_its_speed`] presses with `m g` under
/// its centre while it slides, against the sliding with `μ m g`, and without friction once it
/// rolls (1e-9 N, 1e-12 m: measured at round-off); a box resting on its four corners with its
/// centre of mass off the box's centre has its centre of pressure under the centre of mass (the
/// moments balance) and the weight as its normal force (1e-8 m, measured 3e-10; the force to the resting height's
/// 1e-9 m times the contact's stiffness, 1e-4 N, measured 2e-8; after 3 s of settling as in [`a_box_and_a_capsule_rest_on_their_corners_and_caps_by_hertz_law`]).
#[test]
fn a_contacts_columns_are_its_resultant_force_and_its_centre_of_pressure() {
    let depth = (M * G / K).powf(1.0 / 1.5);
    let table = run(&ball(R - depth, [2.0, 0.0, 0.0], [0.0; 3], 0.2, 0.3, 0.5, 1e-4, 1e-3));
    let col = |n: &str| column(&table, n);
    let t = col("t");
    let star = 2.0 * 2.0 / (7.0 * 0.3 * G);
    let (sliding, rolling) = (t.iter().position(|&s| s >= star / 2.0).unwrap(), t.len() - 1);
    let expected = [(sliding, [-0.3 * M * G, 0.0, M * G]), (rolling, [0.0, 0.0, M * G])];
    for (i, force) in expected {
        for (k, f) in ["fx", "fy", "fz"].iter().zip(force) {
            let got = col(&format!("floor.{k}"))[i];
            assert!((got - f).abs() < 1e-9, "t = {}: floor.{k} = {got}, expected {f}", t[i]);
        }
        assert!((col("floor.normal")[i] - M * G).abs() < 1e-9, "t = {}", t[i]);
        assert!((col("floor.gap")[i] + depth).abs() < 1e-12, "t = {}", t[i]);
        let point = [col("ball.x")[i], col("ball.y")[i], col("ball.z")[i] - R];
        for (k, p) in ["px", "py", "pz"].iter().zip(point) {
            let got = col(&format!("floor.{k}"))[i];
            assert!((got - p).abs() < 1e-12, "t = {}: floor.{k} = {got}, expected {p}", t[i]);
        }
    }
    // The box's centre 0.1 m along x and 0.05 m along y from its centre of mass.
    let scene = on_the_floor(
        "type = \"box-plane\"\nsize = [0.4, 0.3, 0.2]\nat = [0.1, 0.05, 0.1]",
        [0.0217, 0.0417, 0.0533],
        [0.0, 0.0, 0.1],
        ([0.0; 3], [0.0; 3]),
        5.0,
        3.0,
    );
    let table = run(&scene);
    let last = |n: &str| *column(&table, n).last().unwrap();
    for (p, c) in [("px", "x"), ("py", "y")] {
        let (got, under) = (last(&format!("floor.{p}")), last(&format!("solid.{c}")));
        assert!(
            (got - under).abs() < 1e-8,
            "floor.{p} = {got}, the centre of mass at {under}"
        );
    }
    // The normal force's bar is the resting height's (1e-9 m) times the four corners' contact
    // stiffness there, 4 · (3/2) K δ^½ (about 1e5 N/m): the force is the state's, which dopri5
    // holds to its tolerance, not the static closed form's.
    let delta = (2.0 * G / 4.0 / K).powf(1.0 / 1.5);
    let bar = 1e-9 * 4.0 * 1.5 * K * delta.sqrt();
    for k in ["floor.normal", "floor.fz"] {
        let got = last(k);
        assert!((got - 2.0 * G).abs() < bar, "{k} = {got}, expected m g = {}", 2.0 * G);
    }
    assert!(last("floor.gap") < 0.0);
}

/// The planar counterpart of [`a_contacts_columns_are_its_resultant_force_and_its_centre_of_pressure`]:
/// the disk of [`a_disk_thrown_sliding_ends_rolling_at_two_thirds_of_its_speed`] presses with
/// `m g` under its centre and against the sliding with `μ m g` (1e-9 N, 1e-12 m), and a rectangle
/// resting on its two lower vertices with its centre of mass a quarter of the way along has its
/// centre of pressure under the centre of mass and the weight as its normal force (1e-8 m, and
/// the rest height's 1e-9 m times the two vertices' stiffness, about 2e-5 N).
#[test]
fn a_planar_contacts_columns_are_its_resultant_force_and_its_centre_of_pressure() {
    let depth = (M * G / K).powf(1.0 / 1.5);
    let table = run(&disk(R - depth, 2.0, 0.0, 0.2, 0.3, 0.5, 1e-4, 1e-3));
    let col = |n: &str| column(&table, n);
    let star = 2.0 / (3.0 * 0.3 * G);
    let i = col("t").iter().position(|&s| s >= star / 2.0).unwrap();
    let expected = [
        ("ground.fx", -0.3 * M * G, 1e-9),
        ("ground.fy", M * G, 1e-9),
        ("ground.normal", M * G, 1e-9),
        ("ground.gap", -depth, 1e-12),
        ("ground.px", col("disk.x")[i], 1e-12),
        ("ground.py", col("disk.y")[i] - R, 1e-12),
    ];
    for (name, value, bar) in expected {
        let got = col(name)[i];
        assert!((got - value).abs() < bar, "{name} = {got}, expected {value}");
    }
    let rectangle = "type = \"polygon-line\"\nvertices = [[-0.1, 0.0], [0.3, 0.0], [0.3, 0.2], [-0.1, 0.2]]";
    let table = run(&on_the_line(
        rectangle,
        "{ rectangle = [0.4, 0.2] }",
        [0.0, 0.1],
        ([0.0, 0.0], 0.0),
        5.0,
        3.0,
    ));
    let last = |n: &str| *column(&table, n).last().unwrap();
    assert!(
        (last("floor.px") - last("solid.x")).abs() < 1e-8,
        "floor.px = {}, the centre of mass at {}",
        last("floor.px"),
        last("solid.x")
    );
    let delta = (2.0 * G / 2.0 / K).powf(1.0 / 1.5);
    let bar = 1e-9 * 2.0 * 1.5 * K * delta.sqrt();
    for k in ["floor.normal", "floor.fy"] {
        assert!((last(k) - 2.0 * G).abs() < bar, "{k} = {}", last(k));
    }
}
