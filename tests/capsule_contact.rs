//! Compliant contact of two capsules (`capsule-capsule`, `docs/contact.md`, "Capsules") against
//! numbers from elsewhere: a rod resting across a log presses in by Hertz's `(m g / k)^(1/n)`
//! however the element is written (bodies swapped, segments reversed, the whole scene turned);
//! two free capsules striking each other keep their momentum and angular momentum (the contact
//! force acts on both at one point, equal and opposite) with friction and dissipation, and keep
//! their energy without them (the force is the gradient of the potential `k δⁿ⁺¹ / (n + 1)`);
//! rounded segments in the plane (`segment-segment`) strike as capsules in space.

mod common;

use common::{column, run};
use dalembert::Scene;
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};

const G: f64 = 9.81;
const K: f64 = 1e6;

fn fmt(v: &Vector3<f64>) -> String {
    format!("[{:?}, {:?}, {:?}]", v.x, v.y, v.z)
}

/// A rod of 2 kg (a capsule of radius 0.03 along its x axis, half-length 0.2) let down across a
/// log (a capsule of the ground, radius 0.1, along y) under gravity, everything turned by
/// `turn`; `swap` writes the rod first, `reverse` gives each segment's ends the other way round.
fn rod_on_a_log(turn: &UnitQuaternion<f64>, swap: bool, reverse: bool) -> Scene {
    let at = |x: f64, y: f64, z: f64| turn * Vector3::new(x, y, z);
    let mut log = [at(0.0, -1.0, 0.0), at(0.0, 1.0, 0.0)];
    let mut rod = [at(-0.2, 0.0, 0.13), at(0.2, 0.0, 0.13)];
    if reverse {
        log.reverse();
        rod.reverse();
    }
    let segment = |s: &[Vector3<f64>; 2]| format!("[{}, {}]", fmt(&s[0]), fmt(&s[1]));
    let (bodies, segments, radii) = if swap {
        (
            "[\"rod\", \"ground\"]",
            format!("[{}, {}]", segment(&rod), segment(&log)),
            "[0.03, 0.1]",
        )
    } else {
        (
            "[\"ground\", \"rod\"]",
            format!("[{}, {}]", segment(&log), segment(&rod)),
            "[0.1, 0.03]",
        )
    };
    let q = turn.quaternion();
    let text = format!(
        "[scene]\ngravity = {}\n\
         [[bodies]]\nname = \"rod\"\nmass = 2.0\ninertia = [0.0009, 0.0277, 0.0277]\nposition = {}\n\
         orientation = {{ quaternion = [{:?}, {:?}, {:?}, {:?}] }}\n\
         [[forces]]\nname = \"touch\"\ntype = \"capsule-capsule\"\nbodies = {bodies}\nsegments = {segments}\n\
         radii = {radii}\nstiffness = {K}\ndissipation = 5.0\n\
         [simulation]\nend = 3.0\nintegrator = \"dopri5\"\nrtol = 1e-10\natol = 1e-10\noutput_every = 0.01\n",
        fmt(&at(0.0, 0.0, -G)),
        fmt(&at(0.0, 0.0, 0.13)),
        q.w,
        q.i,
        q.j,
        q.k
    );
    Scene::from_toml(&text, "rod on a log").unwrap()
}

#[test]
fn a_rod_resting_across_a_log_presses_in_by_hertz_law() {
    // Set down touching (its axis 0.1 + 0.03 m above the log's) with dissipation, the rod settles
    // on the log's top where the two axes cross, pressing in by δ = (m g / k)^(2/3) (Hertz's
    // exponent 3/2): its centre ends at 0.13 − δ along the turned vertical within 1e-9 m after
    // 3 s (dopri5 at 1e-10; measured 3e-15 m), and the contact's normal force is m g within
    // 1e-6 N, however the element is written.
    let sink = (2.0 * G / K).powf(1.0 / 1.5);
    let turns = [
        UnitQuaternion::identity(),
        UnitQuaternion::from_scaled_axis(Vector3::new(0.3, -0.7, 0.4)),
    ];
    for turn in &turns {
        for (swap, reverse) in [(false, false), (true, false), (false, true), (true, true)] {
            let table = run(&rod_on_a_log(turn, swap, reverse));
            let last = |c: &str| *column(&table, c).last().unwrap();
            let centre = turn.inverse() * Vector3::new(last("rod.x"), last("rod.y"), last("rod.z"));
            let what = format!("turned {:?}, swapped {swap}, reversed {reverse}", turn.scaled_axis());
            assert!(
                (centre.z - (0.13 - sink)).abs() < 1e-9,
                "{what}: rests at height {}, expected {}",
                centre.z,
                0.13 - sink
            );
            // Along the rod and along the log the rest is neutral (nothing pulls it back): the
            // round-off of the turned scene moves it by up to 3e-8 m in 3 s; 1e-6 m bounds that.
            assert!(centre.xy().norm() < 1e-6, "{what}: slid to {centre:?}");
            let normal = last("touch.normal");
            assert!((normal - 2.0 * G).abs() < 1e-6, "{what}: normal force {normal} N");
        }
    }
}

/// The inertia of the two capsules below (body axes, kg·m²): `a`, then `b` upright, then `b`
/// across.
const INERTIA: [[f64; 3]; 3] = [[0.002, 0.03, 0.03], [0.02, 0.02, 0.001], [0.02, 0.001, 0.02]];
const MASS: [f64; 2] = [2.0, 1.5];

/// Two free capsules without gravity, thrown at each other spinning: `a` (radius 0.05, along x,
/// half-length 0.25) at the origin and `b` (radius 0.04, half-length 0.2) above it and off to
/// one side, upright (along z: its lower end strikes `a`'s side) or `across` (along y: the two
/// sides strike); dopri5 at 1e-11.
fn two_capsules(dissipation: f64, friction: f64, across: bool) -> Scene {
    let (b, inertia) = match across {
        false => ("[[0.18, 0.02, 0.15], [0.18, 0.02, 0.55]]", INERTIA[1]),
        true => ("[[0.18, -0.18, 0.35], [0.18, 0.22, 0.35]]", INERTIA[2]),
    };
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, 0.0]\n\
         [[bodies]]\nname = \"a\"\nmass = {}\ninertia = {:?}\nposition = [0.0, 0.0, 0.0]\n\
         velocity = [0.0, 0.0, 0.4]\nangular_velocity = [0.5, 1.0, -2.0]\n\
         [[bodies]]\nname = \"b\"\nmass = {}\ninertia = {:?}\nposition = [0.18, 0.02, 0.35]\n\
         velocity = [-0.1, 0.05, -0.6]\nangular_velocity = [3.0, -1.0, 0.5]\n\
         [[forces]]\nname = \"touch\"\ntype = \"capsule-capsule\"\nbodies = [\"a\", \"b\"]\n\
         segments = [[[-0.25, 0.0, 0.0], [0.25, 0.0, 0.0]], {b}]\n\
         radii = [0.05, 0.04]\nstiffness = {K}\ndissipation = {dissipation}\nfriction = {friction}\n\
         smoothing_velocity = 0.01\n\
         [simulation]\nend = 0.8\nintegrator = \"dopri5\"\nrtol = 1e-11\natol = 1e-11\noutput_every = 0.002\n",
        MASS[0], INERTIA[0], MASS[1], inertia
    );
    Scene::from_toml(&text, "two capsules").unwrap()
}

/// The bodies' momentum and angular momentum about the origin at each output sample, from the
/// table's positions, velocities, Euler parameters and angular velocities (global).
fn momenta(table: &dalembert::output::Table, across: bool) -> Vec<(Vector3<f64>, Vector3<f64>)> {
    let inertia = [INERTIA[0], INERTIA[1 + across as usize]];
    let columns: Vec<Vec<Vec<f64>>> = ["a", "b"]
        .iter()
        .map(|b| {
            [
                "x", "y", "z", "vx", "vy", "vz", "e0", "e1", "e2", "e3", "wx", "wy", "wz",
            ]
            .iter()
            .map(|c| column(table, &format!("{b}.{c}")))
            .collect()
        })
        .collect();
    (0..columns[0][0].len())
        .map(|i| {
            let (mut p, mut h) = (Vector3::zeros(), Vector3::zeros());
            for (k, c) in columns.iter().enumerate() {
                let x = |j: usize| c[j][i];
                let r = Vector3::new(x(0), x(1), x(2));
                let v = Vector3::new(x(3), x(4), x(5));
                let a = UnitQuaternion::from_quaternion(Quaternion::new(x(6), x(7), x(8), x(9)));
                let w = Vector3::new(x(10), x(11), x(12));
                let a = a.to_rotation_matrix();
                let j = a.matrix() * Matrix3::from_diagonal(&Vector3::from(inertia[k])) * a.matrix().transpose();
                p += MASS[k] * v;
                h += MASS[k] * r.cross(&v) + j * w;
            }
            (p, h)
        })
        .collect()
}

#[test]
fn two_capsules_striking_keep_their_momentum_and_angular_momentum() {
    // The contact force acts on the two bodies at one point, equal and opposite, so the total
    // momentum and the angular momentum about the origin are constant through the impact whatever
    // the law (dissipation 0.5 s/m and friction 0.3 here), an end striking a side or two sides
    // striking: both within 1e-10 of their scale (dopri5 at 1e-11; measured 1e-15 and 1e-14:
    // round-off, the forces cancel in every stage).
    for across in [false, true] {
        let table = run(&two_capsules(0.5, 0.3, across));
        let normal = column(&table, "touch.normal");
        assert!(
            normal.iter().any(|&n| n > 1.0),
            "across {across}: the capsules never struck each other"
        );
        let m = momenta(&table, across);
        let (p0, h0) = m[0];
        let scale = 2.0 * 0.6 + 2.0 * 0.4;
        for (i, (p, h)) in m.iter().enumerate() {
            let (dp, dh) = ((p - p0).norm(), (h - h0).norm());
            assert!(
                dp < 1e-10 * scale,
                "across {across}, sample {i}: momentum moved by {dp:e}"
            );
            assert!(
                dh < 1e-10 * scale,
                "across {across}, sample {i}: angular momentum moved by {dh:e}"
            );
        }
    }
}

#[test]
fn two_capsules_striking_without_dissipation_keep_their_energy() {
    // Without dissipation and friction the contact force is the gradient of k δⁿ⁺¹ / (n + 1)
    // (counted in the energy column), so T + V is constant through the impact (a conservation
    // law): within 1e-8 J of about 0.6 J (dopri5 at 1e-11; measured 6.3e-11 J for an end striking
    // a side, 2.1e-10 J for two sides striking).
    for across in [false, true] {
        let table = run(&two_capsules(0.0, 0.0, across));
        let normal = column(&table, "touch.normal");
        assert!(
            normal.iter().any(|&n| n > 1.0),
            "across {across}: the capsules never struck each other"
        );
        let energy = column(&table, "energy");
        let drift = energy.iter().map(|e| (e - energy[0]).abs()).fold(0.0, f64::max);
        assert!(
            drift < 1e-8,
            "across {across}: the energy moved {drift:e} J from {}",
            energy[0]
        );
    }
}

/// The upright case of [`two_capsules`] in the plane z = 0 (`b` along y instead of z, the spins
/// about z): planar rounded segments (`segment-segment`) when `planar`, otherwise spatial
/// capsules; RK4 at 25 μs, output every 2 ms.
fn two_in_the_plane(planar: bool) -> Scene {
    let (a, b) = ("[[-0.25, 0.0], [0.25, 0.0]]", "[[0.18, 0.15], [0.18, 0.55]]");
    let law = format!(
        "radii = [0.05, 0.04]\nstiffness = {K}\ndissipation = 0.5\nfriction = 0.3\nsmoothing_velocity = 0.01\n"
    );
    let run = "[simulation]\nend = 0.8\nintegrator = \"rk4\"\nstep = 2.5e-5\noutput_every = 0.002\n";
    let text = if planar {
        format!(
            "[scene]\ngravity = [0.0, 0.0]\n\
             [[bodies]]\nname = \"a\"\nmass = {}\ninertia = 0.03\nposition = [0.0, 0.0]\nvelocity = [0.0, 0.4]\nangular_velocity = -2.0\n\
             [[bodies]]\nname = \"b\"\nmass = {}\ninertia = 0.02\nposition = [0.18, 0.35]\nvelocity = [-0.1, -0.6]\nangular_velocity = 0.5\n\
             [[forces]]\nname = \"touch\"\ntype = \"segment-segment\"\nbodies = [\"a\", \"b\"]\nsegments = [{a}, {b}]\n{law}{run}",
            MASS[0], MASS[1]
        )
    } else {
        format!(
            "[scene]\ngravity = [0.0, 0.0, 0.0]\n\
             [[bodies]]\nname = \"a\"\nmass = {}\ninertia = [0.002, 0.03, 0.03]\nposition = [0.0, 0.0, 0.0]\nvelocity = [0.0, 0.4, 0.0]\nangular_velocity = [0.0, 0.0, -2.0]\n\
             [[bodies]]\nname = \"b\"\nmass = {}\ninertia = [0.001, 0.02, 0.02]\nposition = [0.18, 0.35, 0.0]\nvelocity = [-0.1, -0.6, 0.0]\nangular_velocity = [0.0, 0.0, 0.5]\n\
             [[forces]]\nname = \"touch\"\ntype = \"capsule-capsule\"\nbodies = [\"a\", \"b\"]\n\
             segments = [[[-0.25, 0.0, 0.0], [0.25, 0.0, 0.0]], [[0.18, 0.15, 0.0], [0.18, 0.55, 0.0]]]\n{law}{run}",
            MASS[0], MASS[1]
        )
    };
    Scene::from_toml(&text, "two in the plane").unwrap()
}

#[test]
fn rounded_segments_in_the_plane_strike_as_capsules_in_space() {
    // segment-segment and capsule-capsule are two programs for one law (the planar and the
    // spatial crate, their own frames and forces): the same strike in the plane z = 0, with
    // friction and dissipation, moves alike (bars below); and the planar run keeps its momentum
    // and its angular momentum about the origin, m (x v_y − y v_x) + J ω, to round-off (bar
    // 1e-11 of 2; measured 5.6e-16 and 1.9e-12).
    let (planar, spatial) = (run(&two_in_the_plane(true)), run(&two_in_the_plane(false)));
    let peak = column(&planar, "touch.normal").into_iter().fold(0.0, f64::max);
    assert!(peak > 1.0, "the segments never struck each other");
    // Bars: positions 1e-12 m (measured 1e-14); velocities and spins 1e-9 m/s and rad/s, the
    // round-off of the contact point times the contact's stiffness through the impact (measured
    // up to 5.9e-11 rad/s); the normal force 1e-10 of its peak (measured 1.3e-11).
    for (p, s, bar) in [
        ("a.x", "a.x", 1e-12),
        ("b.y", "b.y", 1e-12),
        ("a.vy", "a.vy", 1e-9),
        ("a.omega", "a.wz", 1e-9),
        ("b.vx", "b.vx", 1e-9),
        ("b.omega", "b.wz", 1e-9),
        ("touch.normal", "touch.normal", 1e-10 * peak),
    ] {
        let (x, y) = (column(&planar, p), column(&spatial, s));
        assert_eq!(x.len(), y.len());
        let worst = x.iter().zip(&y).fold(0.0f64, |a, (x, y)| a.max((x - y).abs()));
        assert!(worst < bar, "{p}: the plane and space differ by {worst:.2e}");
    }
    let inertia = [0.03, 0.02];
    let momenta: Vec<[f64; 3]> = (0..column(&planar, "t").len())
        .map(|i| {
            let mut out = [0.0; 3];
            for (k, b) in ["a", "b"].iter().enumerate() {
                let c = |n: &str| column(&planar, &format!("{b}.{n}"))[i];
                out[0] += MASS[k] * c("vx");
                out[1] += MASS[k] * c("vy");
                out[2] += MASS[k] * (c("x") * c("vy") - c("y") * c("vx")) + inertia[k] * c("omega");
            }
            out
        })
        .collect();
    for (i, m) in momenta.iter().enumerate() {
        for (c, (x, x0)) in m.iter().zip(&momenta[0]).enumerate() {
            assert!(
                (x - x0).abs() < 1e-11,
                "sample {i}: momentum component {c} moved by {:e}",
                x - x0
            );
        }
    }
}
