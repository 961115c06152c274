//! Spatial force elements against closed forms (each run with Dormand–Prince at 1e-11, so the
//! integration error is ~1e-9 and the tolerances below are 1e-8 unless stated):
//!
//! - a rotational spring–damper about a hinge through the centre of mass: the damped oscillator
//!   `θ = θ₀ + e^{−σt}(A cos ω_d t + B sin ω_d t)`; without damping `T + V` is constant (the
//!   spring's potential is counted);
//! - a spring wound past 0.9π stops the run with the element's name (its angle is known within ±π);
//! - a harmonic torque about a joint axis: `θ = a/(J w)(t − sin(w t)/w)`; between two floating
//!   bodies the same torque leaves the total angular momentum at zero (it acts with opposite signs);
//! - a force in body axes on a body spinning at `Ω`: the centre of mass follows
//!   `r = F/(mΩ) ((1 − cos Ωt)/Ω, t − sin(Ωt)/Ω)`; a global harmonic force `x = a/(m w)(t − sin(wt)/w)`;
//! - a torque in body axes on an axisymmetric spinning body: Euler's equations give
//!   `ω'_x = T/(Jλ) sin λt`, `ω'_y = T/(Jλ)(1 − cos λt)`, `λ = (J_z − J)Ω/J`;
//! - a spring–damper–actuator: a constant actuator tension `F` on a mass on a slider gives
//!   `x = x₀ − F/k (1 − cos √(k/m) t)`;
//! - a user force (linear drag `−b v`): `v = v₀ e^{−bt/m}`.

use dalembert::augmented::Augmented;
use dalembert::integrators::{integrate, IntegratorOptions, Method};
use dalembert::output::Table;
use dalembert::spatial::forces::{Frames, Loads, UserForce};
use dalembert::spatial::{Body, BodyRef, Force, ModelBuilder};
use dalembert::system::MultibodySystem;
use dalembert::{Scene, SceneValue};
use nalgebra::{Matrix3, Quaternion, UnitQuaternion, Vector3};
use std::f64::consts::PI;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

fn run(text: &str, end: f64) -> Result<Table, String> {
    let scene = Scene::from_toml(text, "test").map_err(|e| e.to_string())?;
    let s = scene
        .with_values(&[
            ("simulation.end", end.into()),
            ("simulation.integrator", "dopri5".into()),
            ("simulation.rtol", 1e-11.into()),
            ("simulation.atol", 1e-11.into()),
            ("simulation.step", 1e-4.into()),
            ("simulation.output_every", 0.05.into()),
            ("simulation.formulation", SceneValue::Text("augmented".into())),
        ])
        .map_err(|e| e.to_string())?;
    let rec = s.record(&AtomicBool::new(false));
    rec.outcome.map_err(|e| e.to_string())?;
    Ok(rec.table)
}

/// The body's rotation (body to global) at row `k`.
fn rotation(t: &Table, body: &str, k: usize) -> Matrix3<f64> {
    let e = |c: &str| t.column(&format!("{body}.{c}")).unwrap()[k];
    UnitQuaternion::from_quaternion(Quaternion::new(e("e0"), e("e1"), e("e2"), e("e3")))
        .to_rotation_matrix()
        .into_inner()
}

fn angular_velocity(t: &Table, body: &str, k: usize) -> Vector3<f64> {
    let w = |c: &str| t.column(&format!("{body}.{c}")).unwrap()[k];
    Vector3::new(w("wx"), w("wy"), w("wz"))
}

/// A rod hinged about global z through its centre of mass at the origin (gravity along −z has
/// no moment about the axis), with `forces` appended.
fn hinged(jz: f64, spin: f64, forces: &str) -> String {
    format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"rod\"\nmass = 2.0\ninertia = [0.01, {jz}, {jz}]\nposition = [0.0, 0.0, 0.0]\n\
         angular_velocity = [0.0, 0.0, {spin}]\n\
         [[joints]]\nname = \"hinge\"\ntype = \"revolute\"\nbodies = [\"ground\", \"rod\"]\nat = [0.0, 0.0, 0.0]\naxis = [0.0, 0.0, 1.0]\n\
         {forces}"
    )
}

/// The rod's angle about z at every output row.
fn hinge_angles(t: &Table) -> Vec<f64> {
    let (e0, e3) = (t.column("rod.e0").unwrap(), t.column("rod.e3").unwrap());
    e0.iter().zip(&e3).map(|(c, s)| 2.0 * s.atan2(*c)).collect()
}

#[test]
fn rotational_spring_damper_is_the_damped_oscillator() {
    let (jz, k, c, theta0, w0) = (0.05, 2.0, 0.04, 0.5, 1.5);
    let text = hinged(
        jz,
        w0,
        &format!(
            "[[forces]]\nname = \"spring\"\ntype = \"rotational-spring-damper\"\njoint = \"hinge\"\n\
             stiffness = {k}\ndamping = {c}\nfree_angle = {theta0}\n"
        ),
    );
    let t = run(&text, 3.0).unwrap();
    let (wn, sigma) = ((k / jz).sqrt(), c / (2.0 * jz));
    let wd = (wn * wn - sigma * sigma).sqrt();
    let (a, b) = (-theta0, (w0 - sigma * theta0) / wd);
    let mut worst = 0.0f64;
    for (time, theta) in t.column("t").unwrap().iter().zip(hinge_angles(&t)) {
        let exact = theta0 + (-sigma * time).exp() * (a * (wd * time).cos() + b * (wd * time).sin());
        worst = worst.max((theta - exact).abs());
    }
    assert!(worst < 1e-8, "angle off the damped oscillator by {worst:e} rad");
}

#[test]
fn an_undamped_rotational_spring_keeps_the_energy_it_is_given() {
    // T + V with V = ½ k θ² counted: constant to the integrator's tolerance, while the kinetic
    // energy swaps with the spring's (½ J ω₀² = 0.05625 J).
    let text = hinged(
        0.05,
        1.5,
        "[[forces]]\nname = \"spring\"\ntype = \"rotational-spring-damper\"\njoint = \"hinge\"\nstiffness = 2.0\n",
    );
    let t = run(&text, 2.0).unwrap();
    let energy = t.column("energy").unwrap();
    let drift = energy.iter().fold(0.0f64, |m, e| m.max((e - energy[0]).abs()));
    assert!(drift < 1e-9, "energy drifts by {drift:e} J");
    let theta = hinge_angles(&t);
    let largest = theta.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    // Amplitude ω₀ √(J/k) = 0.2372 rad; the 0.05 s samples see within 1 % of it.
    assert!(
        (largest - 1.5 * (0.05f64 / 2.0).sqrt()).abs() < 3e-3,
        "amplitude {largest}"
    );
}

#[test]
fn a_spring_wound_past_its_range_stops_the_run_with_its_name() {
    // Amplitude ω₀ √(J/k) = 4 rad > 0.9π: the run must stop, not let the torque jump at ±π.
    let text = hinged(
        0.05,
        4.0 * (2.0f64 / 0.05).sqrt(),
        "[[forces]]\nname = \"spring\"\ntype = \"rotational-spring-damper\"\njoint = \"hinge\"\nstiffness = 2.0\n",
    );
    let err = run(&text, 2.0).unwrap_err();
    assert!(err.contains("force 'spring'") && err.contains("0.9π"), "{err}");
}

#[test]
fn a_joint_torque_spins_the_hinge_and_leaves_floating_bodies_without_momentum() {
    let (jz, a, f) = (0.05, 0.3, 0.5);
    let w = 2.0 * PI * f;
    let text = hinged(
        jz,
        0.0,
        &format!(
            "[[forces]]\nname = \"motor\"\ntype = \"torque\"\njoint = \"hinge\"\n\
             value = {{ kind = \"harmonic\", amplitude = {a}, frequency = {f} }}\n"
        ),
    );
    let t = run(&text, 2.0).unwrap();
    let mut worst = 0.0f64;
    for (time, theta) in t.column("t").unwrap().iter().zip(hinge_angles(&t)) {
        let exact = a / (jz * w) * (time - (w * time).sin() / w);
        worst = worst.max((theta - exact).abs());
    }
    assert!(worst < 1e-8, "hinge angle off by {worst:e} rad");

    // Two bodies joined by a hinge about x, floating without gravity: the motor turns one
    // against the other, and the total angular momentum Σ (A J' Aᵀ ω + m r × v) stays zero.
    let floating = "[scene]\ngravity = [0.0, 0.0, 0.0]\n\
         [[bodies]]\nname = \"a\"\nmass = 3.0\ninertia = [0.02, 0.05, 0.06]\nposition = [-0.2, 0.05, 0.0]\n\
         [[bodies]]\nname = \"b\"\nmass = 1.0\ninertia = [0.01, 0.03, 0.02]\nposition = [0.3, 0.0, 0.1]\n\
         [[joints]]\nname = \"hinge\"\ntype = \"revolute\"\nbodies = [\"a\", \"b\"]\nat = [0.0, 0.0, 0.0]\naxis = [1.0, 0.0, 0.0]\n\
         [[forces]]\nname = \"motor\"\ntype = \"torque\"\njoint = \"hinge\"\nvalue = { kind = \"harmonic\", amplitude = 0.5, frequency = 1.0 }\n";
    let t = run(floating, 1.0).unwrap();
    let principal = [(3.0, [0.02, 0.05, 0.06]), (1.0, [0.01, 0.03, 0.02])];
    let mut largest_momentum = 0.0f64;
    let mut spun = 0.0f64;
    for k in 0..t.rows() {
        let mut h = Vector3::zeros();
        for (body, (m, j)) in ["a", "b"].iter().zip(principal) {
            let a = rotation(&t, body, k);
            let w = angular_velocity(&t, body, k);
            let c = |s: &str| t.column(&format!("{body}.{s}")).unwrap()[k];
            let (r, v) = (
                Vector3::new(c("x"), c("y"), c("z")),
                Vector3::new(c("vx"), c("vy"), c("vz")),
            );
            h += a * Matrix3::from_diagonal(&Vector3::from(j)) * a.transpose() * w + m * r.cross(&v);
            spun = spun.max(w.norm());
        }
        largest_momentum = largest_momentum.max(h.norm());
    }
    assert!(spun > 1.0, "the motor turns the bodies: largest |ω| {spun}");
    assert!(largest_momentum < 1e-9, "angular momentum {largest_momentum:e}");
}

/// A free body (no joints, no gravity) with `inertia`, spinning at `spin` about global z, with
/// `forces` appended.
fn free(inertia: [f64; 3], spin: f64, forces: &str) -> String {
    format!(
        "[scene]\ngravity = [0.0, 0.0, 0.0]\n\
         [[bodies]]\nname = \"b\"\nmass = 2.0\ninertia = {inertia:?}\nposition = [0.0, 0.0, 0.0]\n\
         angular_velocity = [0.0, 0.0, {spin}]\n{forces}"
    )
}

#[test]
fn a_force_in_body_axes_turns_with_the_body_and_a_global_one_does_not() {
    let (m, f, spin) = (2.0, 0.7, 3.0);
    let text = free(
        [0.02, 0.02, 0.03],
        spin,
        &format!(
            "[[forces]]\nname = \"push\"\ntype = \"force\"\nbody = \"b\"\nvalue = [{f}, 0.0, 0.0]\nframe = \"body\"\n"
        ),
    );
    let t = run(&text, 2.0).unwrap();
    let c = |s: &str| t.column(s).unwrap();
    let mut worst = 0.0f64;
    for (k, time) in c("t").iter().enumerate() {
        let s = f / (m * spin);
        let (x, y) = (
            s * (1.0 - (spin * time).cos()) / spin,
            s * (time - (spin * time).sin() / spin),
        );
        worst = worst.max((c("b.x")[k] - x).abs()).max((c("b.y")[k] - y).abs());
    }
    assert!(worst < 1e-8, "centre of mass off by {worst:e} m");

    let (a, hz) = (0.4, 0.5);
    let w = 2.0 * PI * hz;
    let text = free(
        [0.02, 0.02, 0.03],
        spin,
        &format!(
            "[[forces]]\nname = \"push\"\ntype = \"force\"\nbody = \"b\"\n\
             fx = {{ kind = \"harmonic\", amplitude = {a}, frequency = {hz} }}\nfz = -0.1\n"
        ),
    );
    let t = run(&text, 2.0).unwrap();
    let c = |s: &str| t.column(s).unwrap();
    let mut worst = 0.0f64;
    for (k, time) in c("t").iter().enumerate() {
        let x = a / (m * w) * (time - (w * time).sin() / w);
        let z = -0.1 / m * time * time / 2.0;
        worst = worst.max((c("b.x")[k] - x).abs()).max((c("b.z")[k] - z).abs());
    }
    assert!(worst < 1e-8, "centre of mass off by {worst:e} m");
}

#[test]
fn a_torque_in_body_axes_follows_eulers_equations() {
    let (j, jz, spin, torque) = (0.02, 0.03, 3.0, 0.01);
    let text = free(
        [j, j, jz],
        spin,
        &format!("[[forces]]\nname = \"kick\"\ntype = \"torque\"\nbody = \"b\"\ntx = {torque}\nframe = \"body\"\n"),
    );
    let t = run(&text, 2.0).unwrap();
    let lambda = (jz - j) * spin / j;
    let amp = torque / (j * lambda);
    let mut worst = 0.0f64;
    for (k, time) in t.column("t").unwrap().iter().enumerate() {
        let body = rotation(&t, "b", k).transpose() * angular_velocity(&t, "b", k);
        let exact = Vector3::new(amp * (lambda * time).sin(), amp * (1.0 - (lambda * time).cos()), spin);
        worst = worst.max((body - exact).norm());
    }
    assert!(
        worst < 1e-8,
        "body angular velocity off Euler's equations by {worst:e} rad/s"
    );
}

#[test]
fn a_spring_damper_actuator_pulls_with_its_tension() {
    let (m, k, pull): (f64, f64, f64) = (1.5, 60.0, 3.0);
    let text = format!(
        "[scene]\ngravity = [0.0, 0.0, -9.81]\n\
         [[bodies]]\nname = \"cart\"\nmass = {m}\ninertia = [0.01, 0.01, 0.01]\nposition = [1.0, 0.0, 0.0]\n\
         [[joints]]\nname = \"rail\"\ntype = \"prismatic\"\nbodies = [\"ground\", \"cart\"]\nat = [1.0, 0.0, 0.0]\naxis = [1.0, 0.0, 0.0]\n\
         [[forces]]\nname = \"cable\"\ntype = \"spring-damper\"\nbodies = [\"ground\", \"cart\"]\n\
         at = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0]]\nstiffness = {k}\nactuator = {{ kind = \"constant\", value = {pull} }}\n"
    );
    let t = run(&text, 2.0).unwrap();
    let wn = (k / m).sqrt();
    let mut worst = 0.0f64;
    for (time, x) in t.column("t").unwrap().iter().zip(t.column("cart.x").unwrap()) {
        worst = worst.max((x - (1.0 - pull / k * (1.0 - (wn * time).cos()))).abs());
    }
    assert!(worst < 1e-8, "cart off by {worst:e} m");
}

/// Linear drag `−b v` on one body: a user force.
#[derive(Debug)]
struct Drag {
    body: BodyRef,
    b: f64,
}

impl UserForce for Drag {
    fn name(&self) -> &str {
        "drag"
    }
    fn bodies(&self) -> Vec<BodyRef> {
        vec![self.body]
    }
    fn add(&self, _t: f64, frames: &Frames<'_>, loads: &mut Loads<'_>) {
        let f = frames.of(self.body);
        loads.force(self.body, &f.r, &(-self.b * f.v));
    }
}

#[test]
fn a_user_force_is_applied_like_the_library_s_own() {
    let (m, b, v0) = (2.0, 0.8, [1.0, -0.5, 2.0]);
    let mut builder = ModelBuilder::new([0.0, 0.0, 0.0]);
    let body = builder.body(Body::new("puck", m, [0.01, 0.02, 0.03]).moving(v0, [0.0, 0.0, 0.0]));
    builder.force(Force::User(Arc::new(Drag { body, b })));
    let model = Arc::new(builder.build().unwrap());
    let (q0, v) = model.initial_state();
    let model: Arc<dyn MultibodySystem> = model;
    let mut f = Augmented::with_defaults(model).unwrap();
    let opts = IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.1);
    let mut worst = 0.0f64;
    integrate(&mut f, 0.0, 2.0, &q0, &v, &opts, &mut |s| {
        let decay = (-b * s.t / m).exp();
        for k in 0..3 {
            worst = worst.max((s.qd[k] - v0[k] * decay).abs());
        }
    })
    .unwrap();
    // RK4 at 1 ms on a decay rate of 0.4/s: local error ~ (h b/m)^5 / 120, far below 1e-12.
    assert!(worst < 1e-12, "velocity off the exponential decay by {worst:e} m/s");

    // A user force on a body the model does not have is refused when the model is built.
    let mut builder = ModelBuilder::new([0.0, 0.0, 0.0]);
    builder.body(Body::new("puck", m, [0.01, 0.01, 0.01]));
    builder.force(Force::User(Arc::new(Drag {
        body: BodyRef::Body(3),
        b,
    })));
    let err = builder.build().unwrap_err().to_string();
    assert!(err.contains("force 'drag'"), "{err}");
}
