//! Every joint kind's `C_q`, `Q_d` and `C_t` against finite differences of `C` along a motion, as
//! the planar joints are tested.
//!
//! Along `q(t) = q ⊕ t v` with constant `v = (ṙ, ω')` the accelerations are zero (`r̈ = 0`, and
//! `p(t) = p ⊗ exp(t ω'/2)` has constant body-frame angular velocity), so
//!
//! ```text
//! dC/dt = C_q v + C_t,    d²C/dt² = −Q_d        (v̇ = 0)
//! ```
//!
//! Central differences: the first derivative with `h = 1e-5` has truncation error `h²C'''/6 ≈ 1e-11`
//! and round-off `1e-16/h ≈ 1e-11` (tolerance 1e-8 on values of order 1); the second with
//! `h = 1e-4`, truncation `h²C''''/12 ≈ 1e-9` and round-off `4e-16/h² ≈ 4e-8` (tolerance 1e-6).

use dalembert_spatial::euler_parameters::from_axis_angle;
use dalembert_spatial::{Body, BodyRef, Driver, DriverTarget, Joint, JointKind, Model, ModelBuilder};
use dalembert_system::{ConstraintSet, MultibodySystem, TimeFunction};
use nalgebra::Vector3;

/// The two bodies of every model here, in general poses.
fn two_bodies(b: &mut ModelBuilder) -> (BodyRef, BodyRef) {
    let first = b.body(
        Body::new("first", 2.0, [0.3, 0.4, 0.5])
            .at([0.2, -0.1, 0.4])
            .oriented(from_axis_angle(&Vector3::new(0.3, 1.0, -0.4), 0.7)),
    );
    let second = b.body(
        Body::new("second", 1.0, [0.2, 0.25, 0.3])
            .at([0.9, 0.3, -0.2])
            .oriented(from_axis_angle(&Vector3::new(-0.6, 0.2, 1.0), -1.1)),
    );
    (first, second)
}

/// Two bodies in general poses, joined by `kind` (or the second joined to the ground).
fn model(kind: JointKind, to_ground: bool) -> Model {
    model_with_driver(kind, to_ground, None)
}

/// [`model`] with a driver of the joint (named "j") or of a body coordinate.
fn model_with_driver(kind: JointKind, to_ground: bool, driver: Option<DriverTarget>) -> Model {
    let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
    let (first, second) = two_bodies(&mut b);
    let i = if to_ground { BodyRef::Ground } else { first };
    let (point, axis, axis_j) = ([0.5, 0.1, 0.1], [0.2, -0.5, 0.8], [0.8, 0.4, 0.05]);
    // The second axis perpendicular to the first (universal and perpendicular joints).
    let a = Vector3::from(axis).normalize();
    let aj = Vector3::from(axis_j);
    let aj = (aj - a * a.dot(&aj)).normalize();
    let joint = match kind {
        JointKind::Distance => Joint::distance("j", i, point, second, [1.1, 0.6, -0.3]),
        JointKind::Universal | JointKind::Perpendicular => Joint::crossed("j", kind, i, second, point, axis, aj.into()),
        _ => Joint::new("j", kind, i, second, point, axis),
    };
    b.joint(joint);
    if let Some(target) = driver {
        let f = TimeFunction::Harmonic {
            offset: 0.1,
            amplitude: 0.4,
            frequency: 0.7,
            phase: 0.3,
        };
        b.driver(Driver::new("motor", target, f));
    }
    b.build().unwrap()
}

/// A state away from the assembled one (so `C ≠ 0` and every term is exercised).
fn state(m: &Model) -> (Vec<f64>, Vec<f64>) {
    let (mut q, _) = m.initial_state();
    let push: Vec<f64> = (0..m.layout().n_v()).map(|k| 0.05 * ((k as f64) * 1.7).sin()).collect();
    m.constraints().correct_positions(&mut q, &push);
    let v = (0..m.layout().n_v())
        .map(|k| 1.3 * ((k as f64) * 0.9 + 0.4).cos())
        .collect();
    (q, v)
}

/// `C` at `(q ⊕ s v, t₀ + s)`.
fn constraint_at(m: &Model, q: &[f64], v: &[f64], t0: f64, s: f64) -> Vec<f64> {
    let mut qt = q.to_vec();
    m.integrate_positions(&mut qt, v, s);
    let mut values = m.values();
    m.evaluate(t0 + s, &qt, &[], &mut values);
    values.c
}

/// Along `(q ⊕ s v, t₀ + s)`: `dC/ds = C_q v + C_t` and `d²C/ds² = −Q_d`, row by row; `passive`
/// models must have `C_t = 0`.
fn check_derivatives(m: &Model, t0: f64, what: &str, passive: bool) {
    let (q, v) = state(m);
    let mut values = m.values();
    m.evaluate(t0, &q, &v, &mut values);
    let rows = ConstraintSet::num_equations(m);
    let mut cq_v = vec![0.0; rows];
    m.jacobian_mul(&values, &v, &mut cq_v);
    let (h1, h2) = (1e-5, 1e-4);
    let (p1, m1) = (constraint_at(m, &q, &v, t0, h1), constraint_at(m, &q, &v, t0, -h1));
    let (p2, m2) = (constraint_at(m, &q, &v, t0, h2), constraint_at(m, &q, &v, t0, -h2));
    for r in 0..rows {
        let rate = (p1[r] - m1[r]) / (2.0 * h1);
        let accel = (p2[r] - 2.0 * values.c[r] + m2[r]) / (h2 * h2);
        let cq = cq_v[r] + values.c_t[r];
        assert!(
            (cq - rate).abs() < 1e-8,
            "{what} row {r}: C_q v + C_t = {cq} vs dC/dt = {rate}"
        );
        let qd = -values.gamma[r];
        assert!(
            (qd - accel).abs() < 1e-6,
            "{what} row {r}: −Q_d = {qd} vs d²C/dt² = {accel}"
        );
        if passive {
            assert_eq!(values.c_t[r], 0.0, "{what} row {r}: a passive joint has no C_t");
        }
    }
}

/// Drivers: joint angle (revolute, cylindrical), joint displacement (prismatic, cylindrical),
/// body coordinate, following a harmonic `f(t)`, at `t₀ = 0.3` (so `f'` and `f''` are not zero).
#[test]
fn driver_terms_match_finite_differences() {
    let cases = [
        (JointKind::Revolute, DriverTarget::JointAngle("j".into())),
        (JointKind::Cylindrical, DriverTarget::JointAngle("j".into())),
        (JointKind::Prismatic, DriverTarget::JointDisplacement("j".into())),
        (JointKind::Cylindrical, DriverTarget::JointDisplacement("j".into())),
        (
            JointKind::Spherical,
            DriverTarget::BodyCoordinate {
                body: BodyRef::Body(1),
                axis: 2,
            },
        ),
    ];
    for (kind, target) in cases {
        for to_ground in [false, true] {
            let what = format!("{} driver {target:?} (ground: {to_ground})", kind.name());
            let m = model_with_driver(kind, to_ground, Some(target.clone()));
            check_derivatives(&m, 0.3, &what, false);
        }
    }
}

#[test]
fn jacobian_and_acceleration_terms_match_finite_differences() {
    for kind in JointKind::ALL {
        for to_ground in [false, true] {
            let m = model(kind, to_ground);
            check_derivatives(&m, 0.0, &format!("{} (ground: {to_ground})", kind.name()), true);
        }
    }
}

/// Assembled where it is placed: every joint's `C` vanishes in the initial configuration, and its
/// equation count is the table's.
#[test]
fn joints_are_satisfied_where_they_are_placed() {
    let counts = [3, 5, 4, 4, 5, 6, 1, 2, 1, 2, 1];
    for (kind, count) in JointKind::ALL.into_iter().zip(counts) {
        let m = model(kind, false);
        let (q, _) = m.initial_state();
        let mut values = m.values();
        m.evaluate(0.0, &q, &[], &mut values);
        assert_eq!(ConstraintSet::num_equations(&m), count, "{}", kind.name());
        let worst = values.c.iter().fold(0.0f64, |a, c| a.max(c.abs()));
        assert!(worst < 1e-15, "{}: |C| = {worst:e}", kind.name());
    }
}

/// Two moving bodies on a revolute joint with the force elements the forced double pendulum of the
/// other tests lacks: a global point force, a body-axes torque, a spring–damper–actuator between
/// the two bodies, and the joint's torque and rotational spring–damper.
fn model_with_forces() -> Model {
    use dalembert_spatial::forces::ForceFrame;
    use dalembert_spatial::Force;
    let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
    let (first, second) = two_bodies(&mut b);
    b.joint(Joint::revolute("j", first, second, [0.5, 0.1, 0.1], [0.2, -0.5, 0.8]));
    let harmonic = TimeFunction::Harmonic {
        offset: 0.2,
        amplitude: 0.7,
        frequency: 0.9,
        phase: 0.1,
    };
    b.force(Force::PointForce {
        name: "push".into(),
        body: first,
        point: [0.3, -0.2, 0.5],
        force: [
            harmonic.clone(),
            TimeFunction::Constant(-1.5),
            TimeFunction::Constant(0.8),
        ],
        frame: ForceFrame::Global,
    });
    b.force(Force::Torque {
        name: "twist".into(),
        body: second,
        torque: [
            TimeFunction::Constant(0.4),
            harmonic.clone(),
            TimeFunction::Constant(-0.6),
        ],
        frame: ForceFrame::Body,
    });
    b.force(Force::SpringDamper {
        name: "link".into(),
        body_i: first,
        point_i: [-0.4, 0.2, 0.1],
        body_j: second,
        point_j: [0.3, 0.5, -0.2],
        stiffness: 30.0,
        damping: 2.0,
        free_length: 0.4,
        actuator: Some(harmonic.clone()),
    });
    b.force(Force::JointTorque {
        name: "motor".into(),
        joint: "j".into(),
        torque: harmonic,
    });
    b.force(Force::RotationalSpringDamper {
        name: "torsion".into(),
        joint: "j".into(),
        stiffness: 8.0,
        damping: 0.6,
        free_angle: -0.3,
    });
    b.build().unwrap()
}

/// `r = M v̇ + C_qᵀ λ − Q` at `(t, q, v)` (the seam's `dynamics_residual`, fresh storage).
fn residual(m: &Model, t: f64, q: &[f64], v: &[f64], vdot: &[f64], lambda: &[f64]) -> Vec<f64> {
    let mut r = vec![0.0; v.len()];
    let (mut mass, mut values) = (m.mass_storage(), m.constraints().values());
    m.dynamics_residual(t, (q, v), (vdot, lambda), (&mut mass, &mut values), &mut r);
    r
}

/// Two moving bodies (or the second and the ground) on a revolute or prismatic joint with a servo
/// following a harmonic target, its torque (or force along the axis) held within `range`.
fn model_with_servo(kind: JointKind, to_ground: bool, range: [f64; 2]) -> Model {
    use dalembert_spatial::Force;
    let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
    let (first, second) = two_bodies(&mut b);
    let i = if to_ground { BodyRef::Ground } else { first };
    b.joint(Joint::new("j", kind, i, second, [0.5, 0.1, 0.1], [0.2, -0.5, 0.8]));
    b.force(Force::JointServo {
        name: "servo".into(),
        joint: "j".into(),
        stiffness: 30.0,
        damping: 2.0,
        target: Some(TimeFunction::Harmonic {
            offset: 0.4,
            amplitude: 0.3,
            frequency: 0.7,
            phase: 0.2,
        }),
        torque: Some(TimeFunction::Constant(0.6)),
        range,
    });
    b.build().unwrap()
}

/// The analytic tangent of the residual (`MultibodySystem::residual_tangent`: each primitive's and
/// force element's wrench derivatives mapped to the body-frame rotation coordinates, and the
/// gyroscopic term) against central differences of `r` along `q ⊕ ε e_j` and `v + ε e_j`, for every
/// joint kind (to another body and to the ground), every driver, and the force elements of
/// [`model_with_forces`] and [`model_with_servo`], at a state off the constraint manifold with multipliers on every
/// equation. Step 1e-6: truncation ≈ 1e-12, round-off ≈ 1e-16 |r| / h ≈ 1e-9;
/// tolerance 1e-6 of the largest entry (at least 1).
#[test]
fn residual_tangent_matches_finite_differences() {
    use dalembert_system::{TangentPattern, TangentValues};
    let mut models: Vec<(String, Model)> = Vec::new();
    for kind in JointKind::ALL {
        for to_ground in [false, true] {
            models.push((format!("{} (ground: {to_ground})", kind.name()), model(kind, to_ground)));
        }
    }
    for (kind, target) in [
        (JointKind::Revolute, DriverTarget::JointAngle("j".into())),
        (JointKind::Cylindrical, DriverTarget::JointDisplacement("j".into())),
        (
            JointKind::Spherical,
            DriverTarget::BodyCoordinate {
                body: BodyRef::Body(1),
                axis: 2,
            },
        ),
    ] {
        for to_ground in [false, true] {
            let name = format!("{} driver {target:?} (ground: {to_ground})", kind.name());
            models.push((name, model_with_driver(kind, to_ground, Some(target.clone()))));
        }
    }
    models.push(("forces on two moving bodies".into(), model_with_forces()));
    // A servo inside its range, and one held at a bound (its torque then does not change with
    // the state; the state's free torque is far from the bound, so the differences do not cross
    // it), about a revolute joint and along a prismatic one.
    for kind in [JointKind::Revolute, JointKind::Prismatic] {
        for to_ground in [false, true] {
            for (what, range) in [("inside its range", [-1e3, 1e3]), ("held at its bound", [0.1, 0.2])] {
                let name = format!("servo {what}, {} (ground: {to_ground})", kind.name());
                models.push((name, model_with_servo(kind, to_ground, range)));
            }
        }
    }
    let t = 0.3;
    for (name, m) in models {
        let (q, v) = state(&m);
        let n = v.len();
        let eqs = ConstraintSet::num_equations(&m);
        let vdot: Vec<f64> = (0..n).map(|k| ((k * 5 % 7) as f64) - 3.0).collect();
        let lambda: Vec<f64> = (0..eqs).map(|k| 2.0 * ((k * 3 % 5) as f64) - 3.5).collect();
        let pattern = TangentPattern::new(&m);
        let (mut dq, mut dv) = (vec![0.0; pattern.len()], vec![0.0; pattern.len()]);
        let mut out = TangentValues::new(&pattern, &mut dq, &mut dv);
        assert!(m.residual_tangent(t, (&q, &v), (&vdot, &lambda), &mut out), "{name}");
        assert!(!out.outside(), "{name}");
        let h = 1e-6;
        for (velocity, got) in [(false, &dq), (true, &dv)] {
            let mut dense = vec![vec![0.0; n]; n];
            for (e, (i, j)) in pattern.entries().enumerate() {
                dense[i][j] = got[e];
            }
            let mut fd = vec![vec![0.0; n]; n];
            for j in 0..n {
                let mut e = vec![0.0; n];
                e[j] = 1.0;
                let mut pm = Vec::new();
                for sign in [1.0, -1.0] {
                    let (mut qs, mut vs) = (q.clone(), v.clone());
                    if velocity {
                        vs[j] += sign * h;
                    } else {
                        m.integrate_positions(&mut qs, &e, sign * h);
                    }
                    pm.push(residual(&m, t, &qs, &vs, &vdot, &lambda));
                }
                for i in 0..n {
                    fd[i][j] = (pm[0][i] - pm[1][i]) / (2.0 * h);
                }
            }
            let scale = fd.iter().flatten().fold(1.0f64, |a, x| a.max(x.abs()));
            for i in 0..n {
                for j in 0..n {
                    assert!(
                        (fd[i][j] - dense[i][j]).abs() <= 1e-6 * scale,
                        "{name}, {} ({i}, {j}): analytic {} vs differences {}",
                        if velocity { "∂r/∂v" } else { "∂r/∂q" },
                        dense[i][j],
                        fd[i][j]
                    );
                }
            }
        }
    }
}
