//! Coulomb friction in a rigid sphere–plane contact, a friction cone (`docs/limits.md`,
//! "Friction in spatial rigid contact"), against closed forms: a ball thrown on a floor slides
//! against its slip velocity, whose direction stays, until it rolls at `v₀ − (2/7) w₀`; a ball
//! thrown across an incline slides along a curve that turns downhill (the classic solution of
//! `ẇ = a e − k ŵ`), until it rolls down at `(5/7) g sin α`; a spinning ball dropped on a floor
//! leaves with the tangential impulse of Coulomb's law, the one that stops its slip or `μ P_n`
//! against the slip; a ball thrown on a plate free to slide keeps the momentum along the plate's
//! guide. Every formulation, RK4 and dopri5, and the energy balance `E − W` closes.

mod common;

use common::{balance_drift, column, run};
use dalembert::Scene;

const G: f64 = 9.81;
const FORMULATIONS: [&str; 3] = ["augmented", "embedding", "amalgamated"];
const METHODS: [&str; 2] = ["rk4", "dopri5"];
/// The ball: 2 kg, radius 0.1 m, solid (`I = (2/5) m R²`).
const M: f64 = 2.0;
const R: f64 = 0.1;

/// RK4's step (s): its truncation error turns the slip's direction near a stop, where the slip
/// velocity is small (the direction of `ẇ = −k ŵ` is neutral: an error across it stays), by
/// 1e-9 at 0.25 m/s with 1 ms and 16 times less with each halving (measured); at 0.25 ms the
/// closed forms below hold to their bars. dopri5 controls it by its tolerance.
const STEP: f64 = 2.5e-4;

type V3 = [f64; 3];

fn add(a: V3, b: V3, s: f64) -> V3 {
    [a[0] + s * b[0], a[1] + s * b[1], a[2] + s * b[2]]
}

fn cross(a: V3, b: V3) -> V3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

fn norm(a: V3) -> f64 {
    (a[0] * a[0] + a[1] * a[1] + a[2] * a[2]).sqrt()
}

/// A ball at `at` with velocity `v` and angular velocity `w` on a plane through the origin with
/// normal `normal` (in the ground, or `plate` for a plate on a guide along x), friction `mu`,
/// restitution `e`.
fn scene(ball: (V3, V3, V3), (normal, mu, e): (V3, f64, f64), plate: bool, run: (&str, &str, f64)) -> Scene {
    let (at, v, w) = ball;
    let (formulation, integrator, end) = run;
    let (plate_text, plane_body) = if plate {
        (
            "[[bodies]]\nname = \"plate\"\nmass = 4.0\nshape = { box = [2.0, 2.0, 0.1] }\nposition = [0.0, 0.0, -0.05]\n\
             [[joints]]\nname = \"guide\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"plate\"]\nat = [0.0, 0.0, -0.05]\naxis = [1.0, 0.0, 0.0]\n",
            "body = \"plate\", ",
        )
    } else {
        ("", "")
    };
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, {}]\n\
         [[bodies]]\nname = \"ball\"\nmass = {M}\nshape = {{ sphere = {R} }}\nposition = {at:?}\nvelocity = {v:?}\nangular_velocity = {w:?}\n\
         {plate_text}\
         [[forces]]\nname = \"floor\"\ntype = \"sphere-plane\"\nbody = \"ball\"\nradius = {R}\n\
         plane = {{ {plane_body}point = [0.0, 0.0, 0.0], normal = {normal:?} }}\nrigid = true\nfriction = {mu}\nrestitution = {e}\n\
         [simulation]\nend = {end}\nformulation = \"{formulation}\"\nintegrator = \"{integrator}\"\n\
         step = {step}\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.01\n",
        -G,
        step = STEP
    );
    Scene::from_toml(&text, "ball").unwrap()
}

/// The columns `<prefix>x`, `y`, `z` of a table at row `k`.
fn vector(c: &dyn Fn(&str) -> Vec<f64>, names: [&str; 3], k: usize) -> V3 {
    [c(names[0])[k], c(names[1])[k], c(names[2])[k]]
}

#[test]
fn a_ball_thrown_on_a_floor_slides_against_its_slip_then_rolls() {
    // The slip velocity `w = v + ω × (−R n)` decelerates at `(7/2) μ g` along its own direction
    // (the friction `−μ m g ŵ` at the contact point: `μ g` on the centre, `(5/2) μ g` from the
    // spin), so it keeps its direction and stops at `t* = 2 |w₀| / (7 μ g)`; the centre moves at
    // `v₀ − μ g t ŵ`, the spin turns at `(5 μ g / (2 R)) n × ŵ`, then it rolls at
    // `v₀ − (2/7) w₀` (its spin about the normal unchanged). The throw is turned about the normal
    // by several angles: the tangents of the plane are fixed, so the slip runs along both rows
    // in different shares, and the result may not depend on it. Bars: 1e-10 m, 1e-9 m/s,
    // 1e-8 rad/s, 1e-9 N: the slip stops at an event located to a thousandth of the stick speed
    // (1e-9 m/s), far below them.
    let mu = 0.3;
    for angle in [0.0f64, 0.7, 2.0, 4.0] {
        let (c, s) = (angle.cos(), angle.sin());
        let turn = |a: V3| [c * a[0] - s * a[1], s * a[0] + c * a[1], a[2]];
        let (v0, w0) = (turn([2.0, 1.0, 0.0]), turn([3.0, -4.0, 2.0]));
        let slip0 = add(v0, cross(w0, [0.0, 0.0, -R]), 1.0);
        let d = [slip0[0] / norm(slip0), slip0[1] / norm(slip0), 0.0];
        let t_star = 2.0 * norm(slip0) / (7.0 * mu * G);
        let exact = |t: f64| {
            let s = t.min(t_star);
            let x = add(
                add([0.0, 0.0, R], v0, t),
                d,
                -0.5 * mu * G * s * s - mu * G * s * (t - s),
            );
            let v = add(v0, d, -mu * G * s);
            let w = add(w0, cross([0.0, 0.0, 1.0], d), 5.0 * mu * G * s / (2.0 * R));
            (x, v, w)
        };
        for formulation in FORMULATIONS {
            for integrator in METHODS {
                let what = format!("{formulation} {integrator}, turned by {angle} rad");
                let scene = scene(
                    ([0.0, 0.0, R], v0, w0),
                    ([0.0, 0.0, 1.0], mu, 0.0),
                    false,
                    (formulation, integrator, 0.6),
                );
                let table = run(&scene);
                let col = |n: &str| column(&table, n);
                let t = col("t");
                let (friction, normal) = (col("floor.friction"), col("floor.normal"));
                for k in 0..t.len() {
                    let (xe, ve, we) = exact(t[k]);
                    let x = vector(&col, ["ball.x", "ball.y", "ball.z"], k);
                    let v = vector(&col, ["ball.vx", "ball.vy", "ball.vz"], k);
                    let w = vector(&col, ["ball.wx", "ball.wy", "ball.wz"], k);
                    assert!(
                        norm(add(x, xe, -1.0)) < 1e-10,
                        "{what}: x({}) = {x:?} against {xe:?}",
                        t[k]
                    );
                    assert!(
                        norm(add(v, ve, -1.0)) < 1e-9,
                        "{what}: v({}) = {v:?} against {ve:?}",
                        t[k]
                    );
                    assert!(
                        norm(add(w, we, -1.0)) < 1e-8,
                        "{what}: ω({}) = {w:?} against {we:?}",
                        t[k]
                    );
                    let f = if t[k] < t_star - 1e-9 { mu * M * G } else { 0.0 };
                    if (t[k] - t_star).abs() > 1e-6 {
                        assert!(
                            (friction[k] - f).abs() < 1e-9,
                            "{what}: friction({}) = {}",
                            t[k],
                            friction[k]
                        );
                    }
                    assert!(
                        (normal[k] - M * G).abs() < 1e-9,
                        "{what}: normal({}) = {}",
                        t[k],
                        normal[k]
                    );
                }
                let drift = balance_drift(&scene);
                assert!(drift < 1e-9, "{what}: E − W moved by {drift:e} J");
            }
        }
    }
}
