//! Library misuse gets errors, not panics: joints built against bodies the model lacks, and
//! slices of the wrong length handed to a formulation (issue: never panic, name what is wrong).

use dalembert::amalgamated::Amalgamated;
use dalembert::augmented::Augmented;
use dalembert::constraints::{Constraint, Gear, Model, Prismatic, Revolute, Rigid};
use dalembert::embedding::Embedding;
use dalembert::kinematics::{Body, BodyId, BodyRef, Vec2};
use dalembert::system::{DynamicsError, Formulation};
use std::sync::Arc;

/// One rod pinned to the ground: `q = [0.5, 0, 0]`.
fn pendulum() -> (Vec<Body>, Vec<f64>) {
    (vec![Body::rod("rod", 1.0, 1.0).unwrap()], vec![0.5, 0.0, 0.0])
}

#[test]
fn joints_on_missing_bodies_are_refused_by_name() {
    let (bodies, q) = pendulum();
    let ghost = BodyRef::Body(BodyId(5));
    let p = Vec2::new(1.0, 0.0);
    let joints: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::at("pin", [BodyRef::Body(BodyId(0)), ghost], p, &q)),
        Box::new(Prismatic::at(
            "slide",
            [ghost, BodyRef::Ground],
            p,
            Vec2::new(1.0, 0.0),
            &q,
        )),
        Box::new(Rigid::at("weld", [BodyRef::Ground, ghost], p, &q)),
        Box::new(Gear::new("gear", [ghost, BodyRef::Body(BodyId(0))], 2.0, &q)),
    ];
    for joint in joints {
        let name = joint.name().to_string();
        let err = Model::new(bodies.clone(), vec![], vec![joint]).unwrap_err().to_string();
        assert_eq!(
            err,
            format!("constraint '{name}': refers to body #5, but the model has 1 moving bodies"),
        );
    }
}

#[test]
fn wrong_slice_lengths_are_errors_in_every_formulation() {
    let (bodies, q) = pendulum();
    let pin = Revolute::at("pin", [BodyRef::Ground, BodyRef::Body(BodyId(0))], Vec2::zeros(), &q);
    let model = Arc::new(Model::new(bodies, vec![], vec![Box::new(pin)]).unwrap());
    let formulations: Vec<Box<dyn Formulation>> = vec![
        Box::new(Augmented::with_defaults(model.clone()).unwrap()),
        Box::new(Embedding::with_defaults(model.clone())),
        Box::new(Amalgamated::with_defaults(model.clone())),
    ];
    for mut f in formulations {
        let (mut qdd, mut lambda) = (vec![0.0; 3], vec![0.0; 2]);
        let qd = [0.0; 3];
        // (q, v = q̇, length of q̈, length of λ, the slice at fault (the seam calls velocities v), its length)
        type Case<'a> = (&'a [f64], &'a [f64], usize, usize, &'static str, usize);
        let cases: [Case; 4] = [
            (&q[..2], &qd, 3, 2, "q", 2),
            (&q, &qd[..1], 3, 2, "v", 1),
            (&q, &qd, 4, 2, "q̈", 4),
            (&q, &qd, 3, 1, "λ", 1),
        ];
        for (qq, vv, nqdd, nl, what, got) in cases {
            let r = f.accelerations(0.0, qq, vv, None, &mut vec![0.0; nqdd], &mut vec![0.0; nl]);
            let expected = if what == "λ" { 2 } else { 3 };
            assert_eq!(
                r,
                Err(DynamicsError::WrongLength { what, expected, got }),
                "{} with {what} of length {got}",
                f.name()
            );
        }
        // The right lengths still work: at rest and without forces every acceleration is zero.
        f.accelerations(0.0, &q, &qd, None, &mut qdd, &mut lambda).unwrap();
        assert!(qdd.iter().all(|a| a.abs() < 1e-12), "{qdd:?}");
    }
}
