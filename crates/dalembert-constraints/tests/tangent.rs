//! The planar model's analytic tangent of the dynamic residual `r = M q̈ + C_qᵀ λ − Q(t, q, q̇)`
//! (`MultibodySystem::residual_tangent`: constraint second derivatives weighted by `λ`, every
//! built-in force element's Jacobians, offset centres of mass) against central differences of `r`
//! (property test).
//!
//! Step 1e-6: truncation O(h²) ≈ 1e-12 times the third derivatives, round-off ≈ 1e-16 |r| / h ≈
//! 1e-8 for residuals of order 100; tolerance 1e-6 relative to the largest entry (at least 1).

use dalembert_constraints::*;
use dalembert_kinematics::{
    Body, BodyId, BodyRef, ForceElement, Gravity, PointForce, RotationalSpringDamper, SpringDamper, Torque, Vec2,
};
use dalembert_system::{ConstraintSet, TimeFunction};
use dalembert_system::{MultibodySystem, TangentPattern, TangentValues};
use proptest::prelude::*;

fn b(i: usize) -> BodyRef {
    BodyRef::Body(BodyId(i))
}

/// Three rods: a pendulum pinned to the ground, a second body on a distance joint and a third on a
/// prismatic joint (the last two with their centres of mass off their reference points: `M(θ)`
/// and the quadratic-velocity force), with every built-in force element.
fn model(q: &[f64], p: &[f64; 6]) -> Model {
    let bodies = vec![
        Body::rod("a", 1.5, 1.0).unwrap(),
        Body::rod("b", 0.7, 0.8)
            .unwrap()
            .with_center_of_mass(Vec2::new(0.2, -0.1))
            .unwrap(),
        Body::rod("c", 2.0, 1.2)
            .unwrap()
            .with_center_of_mass(Vec2::new(-0.15, 0.3))
            .unwrap(),
    ];
    let forces: Vec<Box<dyn ForceElement>> = vec![
        Box::new(Gravity::new(Vec2::new(0.3, -9.81))),
        Box::new(SpringDamper {
            name: "spring ab".into(),
            bodies: (b(0), b(1)),
            points: (Vec2::new(p[0], 0.1), Vec2::new(-0.2, p[1])),
            stiffness: 40.0 + 100.0 * p[2].abs(),
            damping: 3.0,
            free_length: 0.5,
            actuator: Some(TimeFunction::Constant(2.0)),
        }),
        Box::new(SpringDamper {
            name: "spring ground c".into(),
            bodies: (BodyRef::Ground, b(2)),
            points: (Vec2::new(1.0, 2.0), Vec2::new(p[3], 0.2)),
            stiffness: 25.0,
            damping: 1.5,
            free_length: 0.3,
            actuator: None,
        }),
        Box::new(PointForce::constant(
            "push",
            b(1),
            Vec2::new(0.3, p[4]),
            Vec2::new(5.0, -2.0),
        )),
        Box::new(Torque::on("motor", b(2), TimeFunction::Constant(1.5))),
        Box::new(RotationalSpringDamper {
            name: "torsion".into(),
            bodies: (b(0), b(2)),
            stiffness: 12.0,
            damping: 0.8,
            free_angle: p[5],
        }),
    ];
    let constraints: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::at("pin", [BodyRef::Ground, b(0)], Vec2::zeros(), q)),
        Box::new(Distance::between(
            "rod",
            [b(0), b(1)],
            Vec2::new(q[0], q[1]),
            Vec2::new(q[3], q[4]),
            q,
        )),
        Box::new(Prismatic::at(
            "slide",
            [b(1), b(2)],
            Vec2::new(q[6], q[7]),
            Vec2::new(1.0, p[0]),
            q,
        )),
    ];
    Model::new(bodies, forces, constraints).unwrap()
}

/// `r = M q̈ + C_qᵀ λ − Q` at `(t, q, v)` (the seam's `dynamics_residual`, fresh storage).
fn residual(m: &Model, t: f64, q: &[f64], v: &[f64], qdd: &[f64], lambda: &[f64]) -> Vec<f64> {
    let mut r = vec![0.0; v.len()];
    let (mut mass, mut values) = (m.mass_storage(), m.constraints().values());
    m.dynamics_residual(t, (q, v), (qdd, lambda), (&mut mass, &mut values), &mut r);
    r
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, ..ProptestConfig::default() })]

    #[test]
    fn planar_residual_tangent_matches_finite_differences(
        q in prop::collection::vec(-2.0f64..2.0, 9),
        v in prop::collection::vec(-3.0f64..3.0, 9),
        qdd in prop::collection::vec(-5.0f64..5.0, 9),
        lambda in prop::collection::vec(-20.0f64..20.0, 5),
        p in prop::array::uniform6(-1.0f64..1.0),
    ) {
        // Keep the distance joint's points and the springs' ends apart (their derivatives grow
        // like 1/|d|^k, and the elements are singular where the points meet).
        prop_assume!((q[3] - q[0]).hypot(q[4] - q[1]) > 0.3);
        let m = model(&q, &p);
        let t = 0.4;
        let pattern = TangentPattern::new(&m);
        let (mut dq, mut dv) = (vec![0.0; pattern.len()], vec![0.0; pattern.len()]);
        let mut out = TangentValues::new(&pattern, &mut dq, &mut dv);
        prop_assert!(m.residual_tangent(t, (&q, &v), (&qdd, &lambda), &mut out));
        prop_assert!(!out.outside());
        let step = 1e-6;
        for (velocity, got) in [(false, &dq), (true, &dv)] {
            let mut dense = vec![vec![0.0; 9]; 9];
            for (e, (i, j)) in pattern.entries().enumerate() {
                dense[i][j] = got[e];
            }
            let mut fd = vec![vec![0.0; 9]; 9];
            for j in 0..9 {
                let (mut qp, mut qm, mut vp, mut vm) = (q.clone(), q.clone(), v.clone(), v.clone());
                if velocity {
                    vp[j] += step;
                    vm[j] -= step;
                } else {
                    qp[j] += step;
                    qm[j] -= step;
                }
                let rp = residual(&m, t, &qp, &vp, &qdd, &lambda);
                let rm = residual(&m, t, &qm, &vm, &qdd, &lambda);
                for i in 0..9 {
                    fd[i][j] = (rp[i] - rm[i]) / (2.0 * step);
                }
            }
            let scale = fd.iter().flatten().fold(1.0f64, |a, x| a.max(x.abs()));
            for i in 0..9 {
                for j in 0..9 {
                    prop_assert!(
                        (fd[i][j] - dense[i][j]).abs() <= 1e-6 * scale,
                        "{} ({i}, {j}): analytic {} vs differences {}",
                        if velocity { "∂r/∂v" } else { "∂r/∂q" },
                        dense[i][j],
                        fd[i][j]
                    );
                }
            }
        }
    }
}
