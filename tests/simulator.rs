//! The step-by-step simulator: a controller in the loop against the exact discrete-time closed
//! loop, runs advanced in chunks against uninterrupted ones (bitwise, every formulation × method),
//! inputs on forces and drivers, `set_state`, `reset`, and bad requests that leave it usable.

use dalembert::{FormulationKind, Scene, Simulator, SimulatorError};

/// A slider of mass 2 kg on a guide along x (planar), pushed by input `push`, no gravity
/// (`tests/data/pushed-slider.toml`), with the given settings.
fn planar_slider(formulation: &str, integrator: &str, step: f64) -> Scene {
    let mut scene = Scene::from_path("tests/data/pushed-slider.toml").unwrap();
    scene.settings.formulation = FormulationKind::parse(formulation).unwrap();
    scene.settings.method = dalembert::integrators::Method::named(integrator).unwrap();
    scene.settings.step = step;
    scene
}

/// The same slider in a spatial scene (guide along x, force component `fx` an input).
fn spatial_slider(formulation: &str) -> Scene {
    let text = format!(
        r#"
[scene]
gravity = [0.0, 0.0, 0.0]
[[bodies]]
name = "slider"
mass = 2.0
inertia = [0.1, 0.1, 0.1]
position = [0.0, 0.0, 0.0]
[[joints]]
name = "guide"
type = "prismatic"
bodies = ["ground", "slider"]
at = [0.0, 0.0, 0.0]
axis = [1.0, 0.0, 0.0]
[[forces]]
name = "push"
type = "force"
body = "slider"
fx = {{ input = "push" }}
[simulation]
formulation = "{formulation}"
integrator = "rk4"
step = 1e-3
end = 10.0
"#
    );
    Scene::from_toml(&text, "spatial slider").unwrap()
}

/// A proportional-derivative controller holding the slider at `x = 1`, sampled every `period`:
/// `u_k = kp (1 − x_k) − kd v_k`, held over the period. The force is constant over each period, so
/// the motion is a quadratic in time there, which RK4 and Dormand–Prince integrate exactly (and
/// which the Hermite and dense-output interpolants reproduce exactly): the simulator must equal
/// the exact discrete-time closed loop `x_{k+1} = x_k + v_k T + u_k T²/(2m)`,
/// `v_{k+1} = v_k + u_k T/m` to round-off. Tolerance 1e-11: 400 periods of a few hundred steps, each
/// adding round-off of order 1e-16 of the state (|x| ≤ 1.2, |v| ≤ 2).
fn pd_loop(sim: &mut Simulator, period: f64, periods: usize) -> (f64, f64, f64, f64) {
    let (kp, kd, m) = (40.0, 12.0, 2.0);
    let (mut x, mut v) = (0.0f64, 0.0f64);
    for k in 1..=periods {
        let (xs, vs) = (sim.value("slider.x").unwrap(), sim.value("slider.vx").unwrap());
        let u = kp * (1.0 - xs) - kd * vs;
        sim.set_input("push", u).unwrap();
        sim.advance_to(k as f64 * period).unwrap();
        let ue = kp * (1.0 - x) - kd * v;
        x += v * period + ue * period * period / (2.0 * m);
        v += ue * period / m;
    }
    (sim.value("slider.x").unwrap(), sim.value("slider.vx").unwrap(), x, v)
}

#[test]
fn a_pd_controlled_slider_equals_the_discrete_closed_loop() {
    let mut cases: Vec<(String, Scene)> = Vec::new();
    for f in FormulationKind::NAMES {
        cases.push((format!("planar {f} rk4"), planar_slider(f, "rk4", 1e-3)));
        cases.push((format!("planar {f} dopri5"), planar_slider(f, "dopri5", 1e-3)));
        cases.push((format!("spatial {f} rk4"), spatial_slider(f)));
    }
    // A period of five steps (every sample on the grid) and one of 3.7 steps (every sample between
    // two steps: the input's change moves the run there).
    for (what, scene) in &cases {
        for period in [5e-3, 3.7e-3] {
            let mut sim = scene.simulator().unwrap();
            let (x, v, xe, ve) = pd_loop(&mut sim, period, 400);
            assert!(
                (x - xe).abs() < 1e-11 && (v - ve).abs() < 1e-11,
                "{what}, period {period}: x = {x} against {xe}, v = {v} against {ve}"
            );
            // The loop converged toward the set point (a check of the test itself).
            assert!((xe - 1.0).abs() < 0.05, "{what}: x = {xe}");
        }
    }
}

/// The state and time of a simulator, for bitwise comparison.
fn snapshot(sim: &Simulator) -> (f64, Vec<u64>) {
    let (q, v) = sim.state();
    (sim.time(), q.iter().chain(v).map(|x| x.to_bits()).collect())
}

/// Advanced in irregular chunks (reading reactions in between) the run is the uninterrupted one,
/// bitwise, and so is `Simulation::run`'s last sample: every formulation × method, on a planar
/// closed loop with projection, a planar mechanism with a spring–damper and a motor, and a spatial
/// top.
#[test]
fn chunked_runs_equal_uninterrupted_ones_bitwise() {
    let end = 0.4;
    for path in [
        "scenes/four-bar.toml",
        "scenes/slider-crank.toml",
        "scenes/heavy-top.toml",
    ] {
        let base = Scene::from_path(path).unwrap();
        let reaction = base
            .check()
            .unwrap()
            .reactions
            .first()
            .map(|(name, _)| name.clone())
            .unwrap();
        for formulation in FormulationKind::ALL {
            for method in dalembert::integrators::METHODS {
                if method.applies == dalembert::integrators::Applies::AugmentedIndex3
                    && formulation != FormulationKind::Augmented
                {
                    continue;
                }
                let mut scene = base.clone();
                scene.settings.formulation = formulation;
                scene.settings.method = dalembert::integrators::Method::of(method);
                scene.settings.step = 2e-3;
                scene.settings.end = end;
                let what = format!("{path}, {}, {}", formulation.name(), method.name);
                let mut whole = scene.simulator().unwrap();
                whole.advance_to(end).unwrap();
                let mut chunked = scene.simulator().unwrap();
                let mut t = 0.0;
                let mut k = 0;
                while t < end {
                    k += 1;
                    t = (t + 0.0137 * (1.0 + (k % 3) as f64)).min(end);
                    chunked.advance_to(t).unwrap();
                    chunked.value(&reaction).unwrap();
                    if k % 4 == 0 && t < end {
                        chunked.step().unwrap();
                        t = chunked.time();
                    }
                }
                assert_eq!(snapshot(&chunked), snapshot(&whole), "{what}: chunked");
                let mut last = Vec::new();
                scene
                    .simulation()
                    .run(&mut |s| last = s.q.iter().chain(s.qd).map(|x| x.to_bits()).collect())
                    .unwrap();
                assert_eq!(last, snapshot(&whole).1, "{what}: Simulation::run");
            }
        }
    }
}

/// A joint-angle driver whose motion is an input: a set is a step of the prescribed angle from its
/// value in the file, which the projection after the next step enforces.
#[test]
fn a_driver_input_sets_the_prescribed_angle() {
    let text = r#"
[scene]
gravity = [0.0, -9.81]
[[bodies]]
name = "arm"
mass = 1.0
shape = { rod = 1.0 }
position = [0.5, 0.0]
[[joints]]
name = "pivot"
type = "revolute"
bodies = ["ground", "arm"]
at = [0.0, 0.0]
[[drivers]]
name = "servo"
type = "joint-angle"
joint = "pivot"
function = { input = "angle" }
[simulation]
integrator = "rk4"
step = 1e-3
stabilization = "projection"
"#;
    let scene = Scene::from_toml(text, "servo").unwrap();
    assert_eq!(scene.inputs, ["angle"]);
    let mut sim = scene.simulator().unwrap();
    sim.advance_to(0.1).unwrap();
    assert!(
        sim.value("arm.angle").unwrap().abs() < 1e-12,
        "held at the file's angle before a set"
    );
    sim.set_input("angle", 0.3).unwrap();
    sim.step().unwrap();
    let angle = sim.value("arm.angle").unwrap();
    assert!((angle - 0.3).abs() < 1e-10, "angle {angle}");
    // The pin at the origin: the centre of mass at 0.5 (cos 0.3, sin 0.3).
    let x = sim.value("arm.x").unwrap();
    assert!((x - 0.5 * 0.3f64.cos()).abs() < 1e-10, "x {x}");
    // The servo holds the arm against gravity: its effort is the gravity moment m g (L/2) cos θ.
    let effort = sim.value("servo.effort").unwrap().abs();
    assert!((effort - 9.81 * 0.5 * 0.3f64.cos()).abs() < 1e-8, "effort {effort}");
}

/// Every bad request is refused in one line naming what is wrong, and leaves the simulator as it
/// was: the run that follows is bitwise the run without the refused requests.
#[test]
fn bad_requests_leave_the_simulator_usable() {
    let scene = planar_slider("augmented", "rk4", 1e-3);
    let mut sim = scene.simulator().unwrap();
    let mut clean = scene.simulator().unwrap();
    for s in [&mut sim, &mut clean] {
        s.set_input("push", 2.0).unwrap();
        s.advance_to(0.5).unwrap();
    }
    let message = |e: SimulatorError| e.to_string();
    let e = message(sim.set_input("pus", 1.0).unwrap_err());
    assert_eq!(e, "unknown input 'pus' (expected push); did you mean 'push'?");
    let e = message(sim.set_input("push", f64::NAN).unwrap_err());
    assert_eq!(e, "input 'push': NaN is not a finite value");
    let e = message(sim.set_input("push", f64::INFINITY).unwrap_err());
    assert_eq!(e, "input 'push': inf is not a finite value");
    let e = message(sim.advance_to(0.2).unwrap_err());
    assert_eq!(
        e,
        "cannot advance to t = 0.2: the simulator is at t = 0.5 and goes forward only"
    );
    let e = message(sim.advance_to(f64::NAN).unwrap_err());
    assert!(e.starts_with("cannot advance to t = NaN"), "{e}");
    let e = message(sim.value("slider.vz").unwrap_err());
    assert!(e.starts_with("unknown column 'slider.vz'"), "{e}");
    let e = message(sim.set_state(&[0.0; 2], &[0.0; 3]).unwrap_err());
    assert_eq!(
        e,
        "set_state: the model has 3 positions and 3 velocities; 2 and 3 were given"
    );
    let e = message(sim.set_state(&[0.0, f64::NAN, 0.0], &[0.0; 3]).unwrap_err());
    assert_eq!(e, "set_state: slider.y = NaN is not finite");
    assert_eq!(sim.input("push").unwrap(), 2.0);
    for s in [&mut sim, &mut clean] {
        s.advance_to(1.0).unwrap();
    }
    assert_eq!(snapshot(&sim), snapshot(&clean));
    // A model without inputs says so.
    let mut plain = Scene::from_path("scenes/pendulum.toml").unwrap().simulator().unwrap();
    let e = message(plain.set_input("push", 1.0).unwrap_err());
    assert!(e.contains("the model has no inputs"), "{e}");
}

/// `set_state` assembles the state it is given (the least change) and reports how far it moved;
/// the current state given back moves nothing, and the run goes on as before. `reset` returns to
/// the start, and the run after it is the first run again, bitwise.
#[test]
fn set_state_assembles_and_reset_restarts() {
    let scene = Scene::from_path("scenes/four-bar.toml").unwrap();
    let mut sim = scene.simulator().unwrap();
    sim.advance_to(0.3).unwrap();
    let first = snapshot(&sim);
    let (q, v) = (sim.state().0.to_vec(), sim.state().1.to_vec());
    let drift = sim.value("constraint_violation").unwrap();
    assert!(drift < 1e-11, "the run's own drift: {drift}");
    let moved = sim.set_state(&q, &v).unwrap();
    // The assembly removes only the run's drift (its size over the smallest singular value of
    // C_q, of order one for this four-bar): far below any given change.
    assert!(
        moved.positions < 1e-9 && moved.velocities < 1e-9,
        "the run's own state moves by its drift only: {moved:?}"
    );
    let mut off = q.clone();
    off[0] += 1e-3;
    let moved = sim.set_state(&off, &v).unwrap();
    assert!(
        moved.positions > 1e-5 && moved.positions < 2e-3,
        "the assembly moved {moved:?}"
    );
    assert!(sim.value("constraint_violation").unwrap() < 1e-10);
    assert!(sim.value("velocity_violation").unwrap() < 1e-10);
    sim.reset().unwrap();
    assert_eq!(sim.time(), 0.0);
    sim.advance_to(0.3).unwrap();
    assert_eq!(snapshot(&sim), first, "after reset the run is the first one again");
}

/// A body on a revolute pin at its centre (planar, or spatial about z), no gravity, with a force
/// element computed by code (`tests/data/wheel.toml`, `wheel-3d.toml`).
fn pinned(spatial: bool) -> Scene {
    let path = if spatial {
        "tests/data/wheel-3d.toml"
    } else {
        "tests/data/wheel.toml"
    };
    Scene::from_path(path).unwrap()
}

/// A torque from code closes a continuous-time loop: `J θ̈ = −k θ − c θ̇` from `θ = 0`,
/// `θ̇ = 0`, with a constant torque `τ₀` added: the exact motion of the damped oscillator,
/// `θ(t) = θ∞ (1 − e^{−ζωt} (cos ω_d t + ζω/ω_d sin ω_d t))`, `θ∞ = τ₀/k`. RK4 at h = 1 ms on
/// ω = 4 rad/s errs by about (ωh)⁴ ~ 3e-10 of the amplitude over the run: tolerance 1e-8 rad.
/// The force from code (10 N along x) is carried by the pin: its reaction is 10 N.
#[test]
fn a_torque_from_code_follows_the_damped_oscillator() {
    let (j, k, c, tau0): (f64, f64, f64, f64) = (0.5, 8.0, 0.4, 2.0);
    let (w, zeta) = ((k / j).sqrt(), c / (2.0 * (k * j).sqrt()));
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let exact = |t: f64| tau0 / k * (1.0 - (-zeta * w * t).exp() * ((wd * t).cos() + zeta * w / wd * (wd * t).sin()));
    let mut finals = Vec::new();
    for spatial in [false, true] {
        let scene = pinned(spatial);
        assert_eq!(scene.code_forces, ["controller"]);
        let mut sim = scene.simulator().unwrap();
        let theta = std::sync::Arc::new(std::sync::Mutex::new(0.0f64));
        let theta_in = theta.clone();
        sim.set_force("controller", move |_, m| {
            // θ from the rotation matrix: atan2(R10, R00).
            let th = m.rotation[1][0].atan2(m.rotation[0][0]);
            *theta_in.lock().unwrap() = th;
            dalembert::system::inputs::Wrench {
                force: [10.0, 0.0, 0.0],
                torque: [0.0, 0.0, tau0 - k * th - c * m.angular_velocity[2]],
            }
        })
        .unwrap();
        sim.advance_to(3.0).unwrap();
        let th = if spatial {
            let (q, _) = sim.state();
            // Euler parameters (e0, e1, e2, e3) of a rotation about z: θ = 2 atan2(e3, e0).
            2.0 * q[6].atan2(q[3])
        } else {
            sim.value("wheel.angle").unwrap()
        };
        let e = exact(3.0);
        assert!((th - e).abs() < 1e-8, "spatial {spatial}: θ = {th}, exact {e}");
        let fx = sim.value("pin.fx").unwrap();
        assert!((fx.abs() - 10.0).abs() < 1e-9, "spatial {spatial}: pin carries {fx}");
        assert!(*theta.lock().unwrap() != 0.0);
        finals.push(th);
    }
    assert!((finals[0] - finals[1]).abs() < 1e-12, "planar and spatial: {finals:?}");
    // Without a function the element applies nothing: the wheel stays at rest.
    let mut idle = pinned(false).simulator().unwrap();
    idle.advance_to(1.0).unwrap();
    assert_eq!(idle.value("wheel.angle").unwrap(), 0.0);
    let e = idle
        .set_force("controler", |_, _| Default::default())
        .unwrap_err()
        .to_string();
    assert_eq!(
        e,
        "unknown code force 'controler' (expected controller); did you mean 'controller'?"
    );
}
