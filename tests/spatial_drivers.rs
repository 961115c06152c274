//! A spatial driver against the closed form: a rod (mass `m`, centre of mass at `a` from a hinge
//! about global `y`) driven at angle `θ = f(t)` needs the motor torque
//!
//! ```text
//! τ = J_P θ̈ − m g a cos θ,    J_P = J_yy + m a²
//! ```
//!
//! (rotation about `+y` turns the rod from `+x` towards `−z`; gravity's moment about the hinge is
//! `+m g a cos θ` about `y`). Every formulation with RK4 at 1 ms over 2 s: the angle follows `f` and
//! the driver effort equals `τ` to 1e-8 relative (RK4's error at this step is ~1e-12).

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::embedding::Embedding;
use dalembert::integrators::{integrate, IntegratorOptions, Method};
use dalembert::spatial::{Body, BodyRef, Driver, DriverTarget, Joint, ModelBuilder};
use dalembert::system::inverse::InverseDynamics;
use dalembert::system::{Formulation, KinematicOptions, MultibodySystem, TimeFunction};
use std::f64::consts::PI;
use std::sync::Arc;

const M: f64 = 2.0;
const A: f64 = 0.4;
const G: f64 = 9.81;
const J_YY: f64 = 0.05;
const AMPLITUDE: f64 = 0.8;
const FREQUENCY: f64 = 0.5;

/// The driven rod, its angle `θ(t)` and the closed-form torque `τ(t)`.
fn driven_rod() -> (Arc<dalembert::spatial::Model>, impl Fn(f64) -> (f64, f64)) {
    let (m, a, g, j_yy) = (M, A, G, J_YY);
    let (amplitude, frequency) = (AMPLITUDE, FREQUENCY);
    let w = 2.0 * PI * frequency;
    let f = TimeFunction::Harmonic {
        offset: 0.0,
        amplitude,
        frequency,
        phase: 0.0,
    };
    // θ(0) = 0, θ̇(0) = A w: the rod starts along +x turning about +y.
    let omega0 = [0.0, amplitude * w, 0.0];
    let mut b = ModelBuilder::new([0.0, 0.0, -g]);
    let rod = b.body(
        Body::new("rod", m, [0.004, j_yy, j_yy])
            .at([a, 0.0, 0.0])
            .moving([0.0, 0.0, -a * amplitude * w], omega0),
    );
    b.joint(Joint::revolute(
        "hinge",
        BodyRef::Ground,
        rod,
        [0.0; 3],
        [0.0, 1.0, 0.0],
    ));
    b.driver(Driver::new("motor", DriverTarget::JointAngle("hinge".into()), f));
    let j_p = j_yy + m * a * a;
    let closed_form = move |t: f64| {
        let theta = amplitude * (w * t).sin();
        (theta, j_p * (-w * w * theta) - m * g * a * theta.cos())
    };
    (Arc::new(b.build().unwrap()), closed_form)
}

#[test]
fn driven_hinge_needs_the_closed_form_torque() {
    let (model, closed_form) = driven_rod();
    let sys: Arc<dyn MultibodySystem> = model.clone();
    let (q0, v0) = model.initial_state();
    let formulations: Vec<Box<dyn Formulation>> = vec![
        Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
        Box::new(Embedding::with_defaults(sys.clone())),
        Box::new(Amalgamated::with_defaults(sys)),
    ];
    for mut form in formulations {
        let (mut angle_error, mut torque_error, mut samples) = (0.0f64, 0.0f64, 0);
        let opts = IntegratorOptions::fixed(Method::rk4(), 1e-3, 0.05);
        integrate(form.as_mut(), 0.0, 2.0, &q0, &v0, &opts, &mut |s| {
            let (theta, torque) = closed_form(s.t);
            let angle = 2.0 * s.q[5].atan2(s.q[3]);
            angle_error = angle_error.max((angle - theta).abs());
            torque_error = torque_error.max((model.driver_efforts(s.lambda)[0] - torque).abs() / (M * G * A));
            samples += 1;
        })
        .unwrap_or_else(|e| panic!("{}: {e}", form.name()));
        assert_eq!(samples, 41);
        assert!(
            angle_error < 1e-9 && torque_error < 1e-8,
            "{}: angle off by {angle_error:e}, torque by {torque_error:e} (relative)",
            form.name()
        );
    }
}

/// Inverse dynamics on the seam (`dalembert_system::inverse`) runs the fully driven spatial model
/// at any time (no integration): the same closed-form torque, to 1e-10 relative (one position
/// analysis to 1e-12 and one linear solve).
#[test]
fn inverse_dynamics_of_the_driven_hinge_gives_the_closed_form_torque() {
    let (model, closed_form) = driven_rod();
    let (q0, _) = model.initial_state();
    let opts = KinematicOptions {
        tolerance: 1e-12,
        ..Default::default()
    };
    let inverse = InverseDynamics::new(model.clone(), &q0, opts).unwrap();
    for t in [0.0, 0.37, 0.5, 1.234, 1.9] {
        let sol = inverse.solve(t, &q0).unwrap();
        let (theta, torque) = closed_form(t);
        let angle = 2.0 * sol.q[5].atan2(sol.q[3]);
        let effort = model.driver_efforts(&sol.lambda)[0];
        assert!((angle - theta).abs() < 1e-10, "t = {t}: angle {angle} vs {theta}");
        assert!(
            (effort - torque).abs() < 1e-10 * M * G * A,
            "t = {t}: effort {effort} vs {torque}"
        );
    }
}
