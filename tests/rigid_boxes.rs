//! Rigid boxes and capsules on a plane (`docs/limits.md`, "Rigid boxes and capsules on a
//! plane"): a rigid contact of each of a box's corners and of each of a capsule's end spheres,
//! with a friction cone at each, against closed forms. A box sliding flat on a floor slows at
//! `μ g` and stops at `|v₀| / (μ g)`, its bottom corners' normal forces the least-norm ones that
//! balance the friction's tipping moment; a box spinning flat stops at `ω₀ I_z / (μ m g r)`; a
//! box dropped flat bounces flat to `e² h`; a capsule thrown across its axis slides, then rolls
//! at `v₀ / (1 + I / (m r²))`. Every formulation, RK4 and dopri5.

mod common;

use common::{balance_drift, column, run};
use dalembert::Scene;

const G: f64 = 9.81;
const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];
const METHODS: [&str; 2] = ["rk4", "dopri5"];
/// The box: 2 kg, edges 0.4 × 0.2 × 0.1 m.
const M: f64 = 2.0;

/// A box at rest on a floor (its bottom face on z = 0) with velocity `v`, angular velocity `w`,
/// friction `mu`, restitution `e`, dropped from `height` above the floor; `turned` writes the same
/// box as a body turned by a right angle about z with its edges given in that body's axes.
fn box_scene(
    v: [f64; 3],
    w: [f64; 3],
    (mu, e, height): (f64, f64, f64),
    turned: bool,
    run: (&str, &str, f64),
) -> Scene {
    let (formulation, integrator, end) = run;
    let (size, orientation) = if turned {
        (
            "[0.2, 0.4, 0.1]",
            "orientation = { axis = [0.0, 0.0, 1.0], degrees = 90.0 }\n",
        )
    } else {
        ("[0.4, 0.2, 0.1]", "")
    };
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, {}]\n\
         [[bodies]]\nname = \"block\"\nmass = {M}\nshape = {{ box = {size} }}\nposition = [0.0, 0.0, {}]\n{orientation}\
         velocity = {v:?}\nangular_velocity = {w:?}\n\
         [[forces]]\nname = \"floor\"\ntype = \"box-plane\"\nbody = \"block\"\nsize = {size}\n\
         plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\nrigid = true\nfriction = {mu}\nrestitution = {e}\n\
         [simulation]\nend = {end}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
         step = 2.5e-4\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
        -G,
        0.05 + height
    );
    Scene::from_toml(&text, "box").unwrap()
}

/// The bottom corners' normal forces `(x, y, N)` at a row, from the CSV (corners whose gap is
/// zero), `x`, `y` from the box's centre.
fn bottom_forces(c: &dyn Fn(&str) -> Vec<f64>, k: usize) -> Vec<(f64, f64, f64)> {
    let (x, y) = (c("block.x")[k], c("block.y")[k]);
    (0..8)
        .filter(|i| c(&format!("floor.{i}.gap"))[k].abs() < 1e-9)
        .map(|i| {
            let p = |a: &str| c(&format!("floor.{i}.{a}"))[k];
            (p("px") - x, p("py") - y, p("normal"))
        })
        .collect()
}

#[test]
fn a_box_sliding_flat_on_a_floor_stops_at_its_closed_form() {
    // Sliding along `d`, each bottom corner's friction is `−μ N_k d`: the box slows at `μ g` and
    // stops at `t* = |v₀| / (μ g)`, without turning. The friction at the floor, `h/2` below the
    // centre, tips it forward; the bottom corners' normal forces are the least-norm ones that
    // balance that moment (redundant contacts, `docs/sign-conventions.md`):
    // `N = m g / 4 + α x + β y` with `α Σx² = (h/2) μ m g d_x`, `β Σy² = (h/2) μ m g d_y`, equal
    // again once it stops. Written as a body turned by a right angle (its edges in that body's
    // axes): the same box, the same numbers. Bars: 1e-10 m, 1e-9 m/s and rad/s, 1e-9 N.
    let (mu, v0) = (0.3, [2.0f64, 1.0, 0.0]);
    let speed = (v0[0] * v0[0] + v0[1] * v0[1]).sqrt();
    let d = [v0[0] / speed, v0[1] / speed];
    let t_star = speed / (mu * G);
    for turned in [false, true] {
        for formulation in FORMULATIONS {
            for integrator in METHODS {
                let what = format!("{formulation} {integrator}{}", if turned { ", turned" } else { "" });
                let scene = box_scene(v0, [0.0; 3], (mu, 0.0, 0.0), turned, (formulation, integrator, 1.0));
                let table = run(&scene);
                let c = |n: &str| column(&table, n);
                let (t, x, y, vx, wz) = (c("t"), c("block.x"), c("block.y"), c("block.vx"), c("block.wz"));
                for k in 0..t.len() {
                    let s = t[k].min(t_star);
                    let travel = speed * s - 0.5 * mu * G * s * s;
                    assert!((x[k] - d[0] * travel).abs() < 1e-10, "{what}: x({}) = {}", t[k], x[k]);
                    assert!((y[k] - d[1] * travel).abs() < 1e-10, "{what}: y({}) = {}", t[k], y[k]);
                    let ve = d[0] * (speed - mu * G * s);
                    assert!(
                        (vx[k] - ve).abs() < 1e-9,
                        "{what}: vx({}) = {} against {ve}",
                        t[k],
                        vx[k]
                    );
                    assert!(wz[k].abs() < 1e-9, "{what}: turned at {}: {}", t[k], wz[k]);
                    let corners = bottom_forces(&c, k);
                    assert_eq!(corners.len(), 4, "{what}: four corners on the floor at {}", t[k]);
                    let sliding = t[k] < t_star - 1e-6;
                    let tip = if sliding { 0.05 * mu * M * G } else { 0.0 };
                    let (sx, sy): (f64, f64) = (4.0 * 0.2 * 0.2, 4.0 * 0.1 * 0.1);
                    for &(px, py, n) in &corners {
                        let ne = M * G / 4.0 + tip * d[0] / sx * px + tip * d[1] / sy * py;
                        if (t[k] - t_star).abs() > 1e-6 {
                            assert!(
                                (n - ne).abs() < 1e-9,
                                "{what}: corner ({px}, {py}) at {}: N = {n} against {ne}",
                                t[k]
                            );
                        }
                    }
                }
                let drift = balance_drift(&scene);
                assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
            }
        }
    }
}

#[test]
fn a_box_spinning_flat_on_a_floor_stops_at_its_closed_form() {
    // Spinning at ω₀ = 5 rad/s about the vertical, each bottom corner (at `r = √(a² + b²)/2` from
    // the centre) slides across its arm with `μ m g / 4`: the friction's torque `μ m g r`, its
    // force zero, so the corners keep `m g / 4` each and the box spins down at
    // `μ m g r / I_z` (`I_z = m (a² + b²) / 12`) to a stop at `t* = ω₀ I_z / (μ m g r)`, its centre
    // at rest. Bars: 1e-9 rad/s, 1e-10 m, 1e-9 N.
    let (mu, w0) = (0.3, 5.0);
    let r = (0.2f64 * 0.2 + 0.1 * 0.1).sqrt();
    let iz = M * (0.4 * 0.4 + 0.2 * 0.2) / 12.0;
    let rate = mu * M * G * r / iz;
    let t_star = w0 / rate;
    for formulation in FORMULATIONS {
        for integrator in METHODS {
            let what = format!("{formulation} {integrator}");
            let scene = box_scene(
                [0.0; 3],
                [0.0, 0.0, w0],
                (mu, 0.0, 0.0),
                false,
                (formulation, integrator, 0.6),
            );
            let table = run(&scene);
            let c = |n: &str| column(&table, n);
            let (t, x, wz) = (c("t"), c("block.x"), c("block.wz"));
            assert!(t_star > 0.1 && t_star < 0.5, "the stop within the run: {t_star}");
            for k in 0..t.len() {
                let we = (w0 - rate * t[k]).max(0.0);
                assert!(
                    (wz[k] - we).abs() < 1e-9,
                    "{what}: ω({}) = {} against {we}",
                    t[k],
                    wz[k]
                );
                assert!(x[k].abs() < 1e-10, "{what}: the centre moved to {} at {}", x[k], t[k]);
                for (px, py, n) in bottom_forces(&c, k) {
                    assert!(
                        (n - M * G / 4.0).abs() < 1e-9,
                        "{what}: corner ({px}, {py}) at {}: N = {n}",
                        t[k]
                    );
                }
            }
            // The corners' slips turn with the spin, and as they stop their direction's rate
            // `k / |w|` is beyond a fixed step: RK4's balance is 7e-8, 3.4e-9, 3.1e-9, 1e-11 J
            // at 1, 0.5, 0.25, 0.125 ms (measured), dopri5's 5.6e-15 J at 1e-11.
            let bar = if integrator == "rk4" { 1e-8 } else { 1e-9 };
            let drift = balance_drift(&scene);
            assert!(drift < bar, "{what}: E − W moved by {drift:e} J");
        }
    }
}

#[test]
fn a_box_dropped_flat_bounces_flat_to_e_squared_its_height() {
    // Dropped flat from 0.2 m with e = 0.5: its four bottom corners strike together (their
    // impulses solved together, (L9)), so it leaves flat at `e` times its speed and rises to
    // `e² h` = 0.05 m at `t₁ + e v / g`; it does not turn. Bars: 1e-10 m, 1e-9 rad/s.
    let (h, e) = (0.2, 0.5);
    let t1 = (2.0 * h / G).sqrt();
    let apex = t1 + e * G * t1 / G;
    for formulation in FORMULATIONS {
        for integrator in METHODS {
            let what = format!("{formulation} {integrator}");
            let scene = box_scene([0.0; 3], [0.0; 3], (0.3, e, h), false, (formulation, integrator, apex));
            let table = run(&scene);
            let c = |n: &str| column(&table, n);
            let (z, wx, wy) = (c("block.z"), c("block.wx"), c("block.wy"));
            let last = z.len() - 1;
            assert!(
                (z[last] - (0.05 + e * e * h)).abs() < 1e-10,
                "{what}: at the apex z = {} against {}",
                z[last],
                0.05 + e * e * h
            );
            for k in 0..z.len() {
                assert!(
                    wx[k].abs() < 1e-9 && wy[k].abs() < 1e-9,
                    "{what}: turned: ({}, {})",
                    wx[k],
                    wy[k]
                );
            }
        }
    }
}

#[test]
fn a_capsule_thrown_across_its_axis_slides_then_rolls() {
    // A capsule (2 kg, segment 0.6 m along x, radius 0.05 m, `I_x` = 0.004 kg·m²) thrown across
    // its axis at 1 m/s on a floor (μ = 0.2): both end spheres slide with `μ m g / 2`, so the
    // centre slows at `μ g`, the spin about the axis grows at `μ m g r / I_x`, and the contact
    // points' slip `v + ω r` stops at `t* = v₀ / (μ g (1 + m r² / I_x))`; then it rolls at
    // `v₀ / (1 + I_x / (m r²))`. Bars: 1e-10 m, 1e-9 m/s, 1e-8 rad/s.
    let (mu, v0, r, ix) = (0.2, 1.0, 0.05, 0.004);
    let share = 1.0 + M * r * r / ix;
    let t_star = v0 / (mu * G * share);
    for formulation in FORMULATIONS {
        for integrator in METHODS {
            let what = format!("{formulation} {integrator}");
            let text = format!(
                "[scene]\ngravity = [0.0, 0.0, {}]\n\
                 [[bodies]]\nname = \"rod\"\nmass = {M}\ninertia = [{ix}, 0.07, 0.07]\nposition = [0.0, 0.0, {r}]\nvelocity = [0.0, {v0}, 0.0]\n\
                 [[forces]]\nname = \"floor\"\ntype = \"capsule-plane\"\nbody = \"rod\"\nat = [[-0.3, 0.0, {r}], [0.3, 0.0, {r}]]\nradius = {r}\n\
                 plane = {{ point = [0.0, 0.0, 0.0], normal = [0.0, 0.0, 1.0] }}\nrigid = true\nfriction = {mu}\n\
                 [simulation]\nend = 0.5\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
                 step = 2.5e-4\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
                -G
            );
            let scene = Scene::from_toml(&text, "capsule").unwrap();
            let table = run(&scene);
            let c = |n: &str| column(&table, n);
            let (t, y, vy, wx) = (c("t"), c("rod.y"), c("rod.vy"), c("rod.wx"));
            assert!(t_star < 0.4, "the roll within the run: {t_star}");
            for k in 0..t.len() {
                let s = t[k].min(t_star);
                let ye = v0 * s - 0.5 * mu * G * s * s + (v0 - mu * G * s) * (t[k] - s);
                let (ve, we) = (v0 - mu * G * s, -mu * M * G * r / ix * s);
                assert!((y[k] - ye).abs() < 1e-10, "{what}: y({}) = {} against {ye}", t[k], y[k]);
                assert!(
                    (vy[k] - ve).abs() < 1e-9,
                    "{what}: vy({}) = {} against {ve}",
                    t[k],
                    vy[k]
                );
                assert!(
                    (wx[k] - we).abs() < 1e-8,
                    "{what}: ωx({}) = {} against {we}",
                    t[k],
                    wx[k]
                );
            }
            let rolling = v0 * (share - 1.0) / share;
            assert!(
                (vy[vy.len() - 1] - rolling).abs() < 1e-9,
                "{what}: rolls at {} against {rolling}",
                vy[vy.len() - 1]
            );
        }
    }
}
