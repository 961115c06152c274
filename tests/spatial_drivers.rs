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
use dalembert::system::{Formulation, MultibodySystem, TimeFunction};
use std::f64::consts::PI;
use std::sync::Arc;

#[test]
fn driven_hinge_needs_the_closed_form_torque() {
    let (m, a, g, j_yy) = (2.0, 0.4, 9.81, 0.05);
    let (amplitude, frequency) = (0.8, 0.5);
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
    let model = Arc::new(b.build().unwrap());
    let sys: Arc<dyn MultibodySystem> = model.clone();
    let (q0, v0) = model.initial_state();
    let formulations: Vec<Box<dyn Formulation>> = vec![
        Box::new(Augmented::with_defaults(sys.clone()).unwrap()),
        Box::new(Embedding::with_defaults(sys.clone())),
        Box::new(Amalgamated::with_defaults(sys)),
    ];
    let j_p = j_yy + m * a * a;
    for mut form in formulations {
        let (mut angle_error, mut torque_error, mut samples) = (0.0f64, 0.0f64, 0);
        let opts = IntegratorOptions::fixed(Method::Rk4, 1e-3, 0.05);
        integrate(form.as_mut(), 0.0, 2.0, &q0, &v0, &opts, &mut |s| {
            let theta = amplitude * (w * s.t).sin();
            let theta_dd = -w * w * theta;
            let torque = j_p * theta_dd - m * g * a * theta.cos();
            let angle = 2.0 * s.q[5].atan2(s.q[3]);
            angle_error = angle_error.max((angle - theta).abs());
            torque_error = torque_error.max((model.driver_efforts(s.lambda)[0] - torque).abs() / (m * g * a));
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
