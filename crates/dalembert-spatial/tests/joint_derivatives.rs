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
use dalembert_spatial::{Body, BodyRef, Joint, JointKind, Model, ModelBuilder};
use dalembert_system::{ConstraintSet, MultibodySystem};
use nalgebra::Vector3;

/// Two bodies in general poses, joined by `kind` (or the second joined to the ground).
fn model(kind: JointKind, to_ground: bool) -> Model {
    let mut b = ModelBuilder::new([0.0, 0.0, -9.81]);
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

fn constraint_at(m: &Model, q: &[f64], v: &[f64], t: f64) -> Vec<f64> {
    let mut qt = q.to_vec();
    m.integrate_positions(&mut qt, v, t);
    let mut values = m.values();
    m.evaluate(0.0, &qt, &[], &mut values);
    values.c
}

#[test]
fn jacobian_and_acceleration_terms_match_finite_differences() {
    for kind in JointKind::ALL {
        for to_ground in [false, true] {
            let m = model(kind, to_ground);
            let (q, v) = state(&m);
            let mut values = m.values();
            m.evaluate(0.0, &q, &v, &mut values);
            let mut cq_v = vec![0.0; ConstraintSet::num_equations(&m)];
            m.jacobian_mul(&values, &v, &mut cq_v);
            let (h1, h2) = (1e-5, 1e-4);
            let (p1, m1) = (constraint_at(&m, &q, &v, h1), constraint_at(&m, &q, &v, -h1));
            let (p2, m2) = (constraint_at(&m, &q, &v, h2), constraint_at(&m, &q, &v, -h2));
            for r in 0..ConstraintSet::num_equations(&m) {
                let rate = (p1[r] - m1[r]) / (2.0 * h1);
                let accel = (p2[r] - 2.0 * values.c[r] + m2[r]) / (h2 * h2);
                let what = format!("{} (ground: {to_ground}) row {r}", kind.name());
                assert!(
                    (cq_v[r] + values.c_t[r] - rate).abs() < 1e-8,
                    "{what}: C_q v = {} vs dC/dt = {rate}",
                    cq_v[r]
                );
                assert!(
                    (-values.gamma[r] - accel).abs() < 1e-6,
                    "{what}: −Q_d = {} vs d²C/dt² = {accel}",
                    -values.gamma[r]
                );
                assert_eq!(values.c_t[r], 0.0, "{what}: a passive joint has no C_t");
            }
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
