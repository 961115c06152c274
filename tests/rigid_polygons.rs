//! Rigid polygons and rounded segments on a line with friction (`docs/limits.md`, "Rigid
//! polygons and segments"), against the free-body diagram of a block: sliding, it decelerates at
//! `μ g` and its corners carry `m g (1 ± μ h / w) / 2` (the friction below the centre of mass
//! tips it forward), it stops at `v₀² / (2 μ g)` and stays; at rest on an incline its corners carry
//! `m g (cos α ± sin α h / w) / 2` and each half the friction `m g sin α` (the least-norm split of
//! two corners that hold one motion); where `μ h / w > 1` the back corner lifts. Every
//! formulation, RK4 and dopri5; the energy balance closes.

mod common;

use common::{balance_drift, column, run};
use dalembert::Scene;

const G: f64 = 9.81;
const M: f64 = 2.0;
const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];
const METHODS: [&str; 2] = ["rk4", "dopri5"];

/// A block `w × h` (2 kg) resting on a line through the origin at angle `alpha` (its normal
/// `(−sin α, cos α)`), its four corners in rigid contact with it (friction `mu`), thrown at
/// `speed` up the slope; or, `rounded`, a rod of length `w` swept by radius `h / 2` (a
/// `segment-line` element at its two ends).
fn block(w: f64, h: f64, alpha: f64, mu: f64, speed: f64, rounded: bool, run: (&str, &str, f64)) -> Scene {
    let (formulation, integrator, end) = run;
    let n = [-alpha.sin(), alpha.cos()];
    let d = [alpha.cos(), alpha.sin()];
    let at = |u: f64, v: f64| [u * d[0] + v * n[0], u * d[1] + v * n[1]];
    let c = at(0.0, h / 2.0);
    let shape = if rounded {
        let ends = [at(-w / 2.0, h / 2.0), at(w / 2.0, h / 2.0)];
        format!(
            "type = \"segment-line\"\nat = [[{}, {}], [{}, {}]]\nradius = {}\n",
            ends[0][0],
            ends[0][1],
            ends[1][0],
            ends[1][1],
            h / 2.0
        )
    } else {
        // The front lower corner `tilt` higher: the corners' round-off.
        let corners = [at(-w / 2.0, 0.0), at(w / 2.0, 0.0), at(w / 2.0, h), at(-w / 2.0, h)];
        let list: Vec<String> = corners.iter().map(|p| format!("[{}, {}]", p[0], p[1])).collect();
        format!("type = \"polygon-line\"\nvertices = [{}]\n", list.join(", "))
    };
    let text = format!(
        "[scene]\ngravity = [0.0, {}]\n\
         [[bodies]]\nname = \"block\"\nmass = {M}\nshape = {{ rectangle = [{w}, {h}] }}\nposition = [{}, {}]\nangle = {alpha}\n\
         velocity = [{}, {}]\n\
         [[forces]]\nname = \"floor\"\nbody = \"block\"\n{shape}line = {{ point = [0.0, 0.0], normal = [{}, {}] }}\n\
         rigid = true\nfriction = {mu}\n\
         [simulation]\nend = {end}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
         step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
        -G,
        c[0],
        c[1],
        speed * d[0],
        speed * d[1],
        n[0],
        n[1]
    );
    Scene::from_toml(&text, "block").unwrap()
}

#[test]
fn a_block_sliding_on_a_floor_stops_where_coulomb_says_on_the_corners_its_moments_give() {
    // Thrown at 3 m/s on a level floor, μ = 0.4: x = v₀ t − μ g t² / 2 until t* = v₀ / (μ g), then
    // it rests at v₀² / (2 μ g). Sliding, the moments about its centre of mass give the front
    // corner m g (1 + μ h/w) / 2 and the back one m g (1 − μ h/w) / 2, each with friction −μ N;
    // at rest, m g / 2 and no friction. The same for a rounded rod (its ends' circles, radius
    // h/2, centres at ±w/2). Positions to 1e-10 m (the stop is located to 1e-9 m/s of its rate),
    // forces to 1e-9 N, at rest it stays to 1e-12 m and 1e-12 rad.
    let (v0, mu, w, h) = (3.0, 0.4, 0.4, 0.2);
    let t_star = v0 / (mu * G);
    for rounded in [false, true] {
        // The corners and ends are listed back (−w/2) first.
        let (front, back) = ("floor.1", "floor.0");
        for formulation in FORMULATIONS {
            for integrator in METHODS {
                let scene = block(w, h, 0.0, mu, v0, rounded, (formulation, integrator, 1.2));
                let what = format!("{formulation} {integrator}{}", if rounded { ", rounded" } else { "" });
                let table = run(&scene);
                let c = |n: &str| column(&table, n);
                let (t, x, y, angle) = (c("t"), c("block.x"), c("block.y"), c("block.angle"));
                let (nf, nb) = (c(&format!("{front}.normal")), c(&format!("{back}.normal")));
                let (ff, fb) = (c(&format!("{front}.friction")), c(&format!("{back}.friction")));
                for k in 0..t.len() {
                    let s = t[k].min(t_star);
                    let xe = v0 * s - 0.5 * mu * G * s * s;
                    assert!((x[k] - xe).abs() < 1e-10, "{what}: x({}) = {} against {xe}", t[k], x[k]);
                    assert!(
                        (y[k] - h / 2.0).abs() < 1e-12 && angle[k].abs() < 1e-12,
                        "{what}: it left the floor at {}",
                        t[k]
                    );
                    if (t[k] - t_star).abs() < 2e-3 {
                        continue;
                    }
                    let (share, f) = if t[k] < t_star { (mu * h / w, mu) } else { (0.0, 0.0) };
                    let (nfe, nbe) = (M * G * (1.0 + share) / 2.0, M * G * (1.0 - share) / 2.0);
                    assert!(
                        (nf[k] - nfe).abs() < 1e-9 && (nb[k] - nbe).abs() < 1e-9,
                        "{what}: corners {} {} at {}",
                        nf[k],
                        nb[k],
                        t[k]
                    );
                    assert!(
                        (ff[k] + f * nfe).abs() < 1e-9 && (fb[k] + f * nbe).abs() < 1e-9,
                        "{what}: friction {} {} at {}",
                        ff[k],
                        fb[k],
                        t[k]
                    );
                }
                let drift = balance_drift(&scene);
                assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
            }
        }
    }
}

#[test]
fn a_block_at_rest_on_an_incline_stays_with_its_corners_loads_and_half_the_friction_each() {
    // α = 0.3 rad, μ = 0.6 > tan α: it stays (1e-12 m). The corners hold one motion, so only the
    // sum of their friction forces is determined, m g sin α; the least-norm split is half each,
    // within each corner's μ N. The moments give the lower corner m g (cos α + sin α h/w) / 2 and
    // the upper one m g (cos α − sin α h/w) / 2.
    let (alpha, mu, w, h) = (0.3f64, 0.6, 0.4, 0.2);
    let lower = M * G * (alpha.cos() + alpha.sin() * h / w) / 2.0;
    let upper = M * G * (alpha.cos() - alpha.sin() * h / w) / 2.0;
    let share = M * G * alpha.sin() / 2.0;
    assert!(share < mu * upper);
    for formulation in FORMULATIONS {
        for integrator in METHODS {
            let scene = block(w, h, alpha, mu, 0.0, false, (formulation, integrator, 2.0));
            let what = format!("{formulation} {integrator}");
            let table = run(&scene);
            let c = |n: &str| column(&table, n);
            let (x, y, angle) = (c("block.x"), c("block.y"), c("block.angle"));
            let (n0, n1, f0, f1) = (
                c("floor.0.normal"),
                c("floor.1.normal"),
                c("floor.0.friction"),
                c("floor.1.friction"),
            );
            for k in 0..x.len() {
                let moved = (x[k] - x[0])
                    .abs()
                    .max((y[k] - y[0]).abs())
                    .max((angle[k] - alpha).abs());
                assert!(moved < 1e-12, "{what}: it moved by {moved:e}");
                assert!(
                    (n0[k] - lower).abs() < 1e-9 && (n1[k] - upper).abs() < 1e-9,
                    "{what}: corners {} {}",
                    n0[k],
                    n1[k]
                );
                assert!(
                    (f0[k] - share).abs() < 1e-9 && (f1[k] - share).abs() < 1e-9,
                    "{what}: friction {} {}",
                    f0[k],
                    f1[k]
                );
            }
        }
    }
}

#[test]
fn a_sliding_block_tips_where_its_friction_moment_passes_its_weight_moment() {
    // Sliding, the back corner carries m g (1 − μ h/w) / 2: where μ h / w < 1 it stays down, where
    // μ h / w > 1 that would pull, and the back corner lifts at once (μ = 0.5; h/w = 1.6, 2.5;
    // over 0.2 s it rises 6e-2 m).
    let (v0, mu, h) = (2.0, 0.5, 0.4);
    for (w, lifts) in [(0.25, false), (0.16, true)] {
        assert_eq!(mu * h / w > 1.0, lifts);
        for formulation in FORMULATIONS {
            let scene = block(w, h, 0.0, mu, v0, false, (formulation, "rk4", 0.2));
            let table = run(&scene);
            let back = column(&table, "floor.0.gap");
            let front = column(&table, "floor.1.gap");
            let highest = back.iter().fold(0.0f64, |m, g| m.max(*g));
            // The front corner stays on the floor: to round-off while the block slides flat; held
            // at the acceleration level while it pivots on it, to RK4's error (2.2e-12 m).
            let front_off = front.iter().fold(0.0f64, |m, g| m.max(g.abs()));
            let bar = if lifts { 1e-10 } else { 1e-15 };
            assert!(
                front_off < bar,
                "{formulation}, w = {w}: the front corner is {front_off:e} m off the floor"
            );
            if lifts {
                assert!(
                    highest > 1e-4,
                    "{formulation}, w = {w}: the back corner stayed down ({highest:e} m)"
                );
            } else {
                assert!(
                    highest < 1e-12,
                    "{formulation}, w = {w}: the back corner lifted by {highest:e} m"
                );
            }
        }
    }
}

/// A block `0.4 × 0.2` m (2 kg) held level with its lower face `drop` above a floor, its centre
/// of mass `offset` along the face from the face's middle, released; its corners listed from
/// `first` on (0: back lower, 1: front lower, 2: front upper, 3: back upper), backwards where
/// `reversed`; moving forwards at `speed`; its front lower corner `tilt` higher than the back one.
/// The floor's restitution `e`, friction `mu`.
fn dropped_block(
    (offset, drop, speed, tilt): (f64, f64, f64, f64),
    (e, mu): (f64, f64),
    (first, reversed): (usize, bool),
    run: (&str, &str, f64),
) -> Scene {
    let (formulation, integrator, end) = run;
    let (w, h) = (0.4, 0.2);
    // The front lower corner `tilt` higher: the corners' round-off.
    let corners = [
        [-w / 2.0, drop],
        [w / 2.0, drop + tilt],
        [w / 2.0, drop + h],
        [-w / 2.0, drop + h],
    ];
    let mut order: Vec<usize> = (0..4).map(|i| (first + i) % 4).collect();
    if reversed {
        order.reverse();
    }
    let list: Vec<String> = order
        .iter()
        .map(|&i| format!("[{}, {}]", corners[i][0], corners[i][1]))
        .collect();
    let text = format!(
        "[scene]\ngravity = [0.0, {}]\n\
         [[bodies]]\nname = \"block\"\nmass = {M}\nshape = {{ rectangle = [{w}, {h}] }}\nposition = [{offset}, {}]\nvelocity = [{speed}, 0.0]\n\
         [[forces]]\nname = \"floor\"\nbody = \"block\"\ntype = \"polygon-line\"\nvertices = [{}]\n\
         line = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}\nrigid = true\nfriction = {mu}\nrestitution = {e}\n\
         [simulation]\nend = {end}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
         step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
        -G,
        drop + h / 2.0,
        list.join(", "),
    );
    Scene::from_toml(&text, "dropped block").unwrap()
}

#[test]
fn a_block_landing_flat_bounces_flat_whatever_the_order_of_its_corners() {
    // Dropped level from 0.1 m onto a floor with e = 0.5: its two lower corners strike at once,
    // at v = √(2 g d), and Newton's law at both, solved together (L9), sends it up at e v with
    // no turn: pure translation is the solution where the centre of mass lies between the
    // corners, whatever its place (the corners' impulses share the momentum by the moments), so
    // it rises to e² d and lands flat again. Taken one corner at a time, the first impulse
    // turned it and the result hung on the corners' order. Centre of mass in the middle and
    // 0.12 m off it; the corners in four orders, and the front one listed 1e-15 m higher or
    // lower (within 1e-12 m of the floor, they strike together); without friction, and with
    // μ = 0.4 while it
    // also moves forwards at 3 m/s: both corners then slip through the impact (stopping the
    // slip would take 6 N·s, beyond μ (1 + e) m v = 1.68 N·s), each with the tangential impulse
    // μ P_n, which leaves it at 3 − μ (1 + e) v forwards, still with no turn (both corners leave
    // at e v). Positions to 1e-10 m (free flight is exact in both methods; the impact is located
    // to 1e-14 of its gap), the turn to 1e-12 rad, and the energy balance with the impact's loss
    // to 1e-9 J.
    let (drop, e) = (0.1, 0.5);
    let v = (2.0 * G * drop).sqrt();
    let (t1, t2) = (v / G, v / G + 2.0 * e * v / G);
    let height = |t: f64| {
        if t <= t1 {
            drop - 0.5 * G * t * t
        } else {
            let s = t - t1;
            e * v * s - 0.5 * G * s * s
        }
    };
    for offset in [0.0, 0.12] {
        for (order, mu, u, tilt) in [
            ((0, false), 0.0, 0.0, 0.0),
            ((1, false), 0.4, 3.0, 0.0),
            ((2, true), 0.0, 0.0, 0.0),
            ((3, true), 0.4, 3.0, 0.0),
            ((0, false), 0.0, 0.0, 1e-15),
            ((0, false), 0.4, 3.0, -1e-15),
        ] {
            let after = u - mu * (1.0 + e) * v;
            let along = |t: f64| offset + u * t.min(t1) + after * (t - t1).max(0.0);
            for formulation in FORMULATIONS {
                for integrator in METHODS {
                    let scene = dropped_block((offset, drop, u, tilt), (e, mu), order, (formulation, integrator, 0.28));
                    let what = format!(
                        "{formulation} {integrator}, offset {offset}, order {order:?}, μ = {mu}, tilt {tilt:e}"
                    );
                    let table = run(&scene);
                    let c = |n: &str| column(&table, n);
                    let (t, x, y, angle) = (c("t"), c("block.x"), c("block.y"), c("block.angle"));
                    assert!(t[t.len() - 1] < t2, "the run ends before the second landing");
                    for k in 0..t.len() {
                        let (xe, ye) = (along(t[k]), height(t[k]) + 0.1);
                        assert!(
                            (y[k] - ye).abs() < 1e-10 && (x[k] - xe).abs() < 1e-10,
                            "{what}: ({}, {}) at {} against ({xe}, {ye})",
                            x[k],
                            y[k],
                            t[k]
                        );
                        assert!(
                            angle[k].abs() < 1e-12,
                            "{what}: it turned by {:e} at {}",
                            angle[k],
                            t[k]
                        );
                    }
                    let drift = balance_drift(&scene);
                    assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
                }
            }
        }
    }
}

#[test]
fn a_wedge_stuck_on_an_incline_stays_stuck_through_an_impact_on_it() {
    // A wedge (2 kg) at rest on an incline of 0.3 rad with μ = 0.6 > tan α, its lower corners in
    // rigid contact with the incline and its upper face level; a ball (0.5 kg) dropped 0.2 m onto
    // that face above the wedge's middle, e = 0.5. The ball's vertical impulse J pushes the wedge
    // downhill by J sin α and into the incline by J cos α: the corners' friction impulses (L6)
    // hold it while J sin α ≤ μ J cos α, as its weight is held. So the wedge does not move
    // (1e-12 m and rad), and the ball meets an immovable face: it leaves at e v and rises to
    // e² × 0.2 m (1e-10 m). Without the held corners' friction in the impulse the wedge slid off
    // at the impact.
    let (alpha, mu, w, e, drop, r) = (0.3f64, 0.6, 0.4, 0.5, 0.2, 0.05);
    let d = [alpha.cos(), alpha.sin()];
    let (b0, b1) = ([-w / 2.0 * d[0], -w / 2.0 * d[1]], [w / 2.0 * d[0], w / 2.0 * d[1]]);
    let top = 0.3;
    let v = (2.0 * G * drop).sqrt();
    let (t1, t2) = (v / G, v / G + 2.0 * e * v / G);
    for formulation in FORMULATIONS {
        for integrator in METHODS {
            let text = format!(
                "[scene]\ngravity = [0.0, {}]\n\
                 [[bodies]]\nname = \"wedge\"\nmass = {M}\nshape = {{ rectangle = [0.4, 0.3] }}\nposition = [0.0, 0.15]\n\
                 [[bodies]]\nname = \"ball\"\nmass = 0.5\nshape = {{ disk = {r} }}\nposition = [0.0, {}]\n\
                 [[forces]]\nname = \"incline\"\ntype = \"polygon-line\"\nbody = \"wedge\"\n\
                 vertices = [[{}, {}], [{}, {}], [{}, {top}], [{}, {top}]]\n\
                 line = {{ point = [0.0, 0.0], normal = [{}, {}] }}\nrigid = true\nfriction = {mu}\n\
                 [[forces]]\nname = \"face\"\ntype = \"circle-line\"\nbody = \"ball\"\nradius = {r}\n\
                 line = {{ body = \"wedge\", point = [0.0, {top}], normal = [0.0, 1.0] }}\nrigid = true\nrestitution = {e}\n\
                 [simulation]\nend = 0.35\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
                 step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
                -G,
                top + r + drop,
                b0[0],
                b0[1],
                b1[0],
                b1[1],
                b1[0],
                b0[0],
                -alpha.sin(),
                alpha.cos(),
            );
            let scene = Scene::from_toml(&text, "wedge").unwrap();
            let what = format!("{formulation} {integrator}");
            let table = run(&scene);
            let c = |n: &str| column(&table, n);
            let (t, x, y, ball) = (c("t"), c("wedge.x"), c("wedge.y"), c("ball.y"));
            let turn = c("wedge.angle");
            assert!(t[t.len() - 1] < t2, "the run ends before the ball's second landing");
            for k in 0..t.len() {
                let moved = x[k].abs().max((y[k] - 0.15).abs()).max(turn[k].abs());
                assert!(moved < 1e-12, "{what}: the wedge moved by {moved:e} at {}", t[k]);
                let s = t[k] - t1;
                let expected = if s <= 0.0 {
                    top + r + drop - 0.5 * G * t[k] * t[k]
                } else {
                    top + r + e * v * s - 0.5 * G * s * s
                };
                assert!(
                    (ball[k] - expected).abs() < 1e-10,
                    "{what}: the ball at {} m at {}, against {expected}",
                    ball[k],
                    t[k]
                );
            }
        }
    }
}

#[test]
fn a_block_sliding_on_a_floor_takes_its_friction_impulse_when_a_ball_strikes_it() {
    // A block (2 kg, 0.4 × 0.2 m) sliding on a level floor, both lower corners in rigid contact
    // with it, μ = 0.4; a ball (0.5 kg) dropped 0.2 m lands on its upper face above its middle,
    // e = 0.5, at t₁ = √(2 × 0.2 / g). The ball leaves at e v, so its impulse is J = m (1 + e) v,
    // all of it passed to the floor through the held corners; their friction impulses (L6),
    // μ J while the block still slips, slow it by μ J / M at once. So the block's speed is
    // u₀ − μ g t before t₁ and u₀ − μ g t − μ J / M after (1e-10 m/s, its position 1e-10 m),
    // without turning (1e-12 rad). Where its speed at t₁ is less than μ J / M (0.1 m/s here
    // against 0.297 m/s), the impact stops it and it stays (1e-10 m). Without the held corners'
    // slipping friction in the impulse, the block kept its speed through the impact.
    let (mu, e, drop, r, m) = (0.4f64, 0.5, 0.2, 0.05, 0.5);
    let v = (2.0 * G * drop).sqrt();
    let t1 = v / G;
    let j = m * (1.0 + e) * v;
    let kick = mu * j / M;
    for speed_at_impact in [2.2, 0.1] {
        let u0 = speed_at_impact + mu * G * t1;
        // Centred under the ball at the impact.
        let x0 = -(u0 * t1 - 0.5 * mu * G * t1 * t1);
        for formulation in FORMULATIONS {
            for integrator in METHODS {
                let text = format!(
                    "[scene]\ngravity = [0.0, {}]\n\
                     [[bodies]]\nname = \"block\"\nmass = {M}\nshape = {{ rectangle = [0.4, 0.2] }}\nposition = [{x0}, 0.1]\n\
                     velocity = [{u0}, 0.0]\n\
                     [[bodies]]\nname = \"ball\"\nmass = {m}\nshape = {{ disk = {r} }}\nposition = [0.0, {}]\n\
                     [[forces]]\nname = \"floor\"\ntype = \"polygon-line\"\nbody = \"block\"\n\
                     vertices = [[{}, 0.0], [{}, 0.0], [{}, 0.2], [{}, 0.2]]\n\
                     line = {{ point = [0.0, 0.0], normal = [0.0, 1.0] }}\nrigid = true\nfriction = {mu}\n\
                     [[forces]]\nname = \"face\"\ntype = \"circle-line\"\nbody = \"ball\"\nradius = {r}\n\
                     line = {{ body = \"block\", point = [{x0}, 0.2], normal = [0.0, 1.0] }}\nrigid = true\nrestitution = {e}\n\
                     [simulation]\nend = {}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
                     step = 1e-3\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
                    -G,
                    0.2 + r + drop,
                    x0 - 0.2,
                    x0 + 0.2,
                    x0 + 0.2,
                    x0 - 0.2,
                    // Before the ball's second landing.
                    t1 + 0.15,
                );
                let scene = Scene::from_toml(&text, "struck block").unwrap();
                let what = format!("{speed_at_impact} m/s {formulation} {integrator}");
                let table = run(&scene);
                let c = |n: &str| column(&table, n);
                let (t, x, u, y, turn) = (c("t"), c("block.x"), c("block.vx"), c("block.y"), c("block.angle"));
                for k in 0..t.len() {
                    let (xe, ue) = if t[k] <= t1 {
                        (x0 + u0 * t[k] - 0.5 * mu * G * t[k] * t[k], u0 - mu * G * t[k])
                    } else if speed_at_impact > kick {
                        let s = t[k] - t1;
                        let after = speed_at_impact - kick;
                        (after * s - 0.5 * mu * G * s * s, after - mu * G * s)
                    } else {
                        (0.0, 0.0)
                    };
                    assert!(
                        (x[k] - xe).abs() < 1e-10 && (u[k] - ue).abs() < 1e-10,
                        "{what}: at {} the block is at {} m, {} m/s, against {xe}, {ue}",
                        t[k],
                        x[k],
                        u[k]
                    );
                    let moved = (y[k] - 0.1).abs().max(turn[k].abs());
                    assert!(
                        moved < 1e-12,
                        "{what}: the block rose or turned by {moved:e} at {}",
                        t[k]
                    );
                }
            }
        }
    }
}
