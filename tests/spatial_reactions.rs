//! Spatial joint reactions (`Model::reactions`, `docs/sign-conventions.md`: what the second body
//! exerts on the first, moment about the joint's point on the first body) against statics, a
//! closed form and the Newton–Euler equations of the body. Tolerance 1e-9 relative: the multipliers
//! come from one linear solve of a well-conditioned system (round-off ~1e-14).

use dalembert::augmented::Augmented;
use dalembert::spatial::euler_parameters::{from_axis_angle, rotation};
use dalembert::spatial::{Body, BodyRef, Joint, JointKind, Model, ModelBuilder};
use dalembert::system::{Formulation, MultibodySystem};
use nalgebra::{Matrix3, Vector3};
use std::sync::Arc;

const G: f64 = 9.81;

/// `(v̇, λ)` at the model's initial state, from the augmented formulation.
fn solve(model: &Arc<Model>) -> (Vec<f64>, Vec<f64>) {
    let sys: Arc<dyn MultibodySystem> = model.clone();
    let mut f = Augmented::with_defaults(sys).unwrap();
    let (q, v) = model.initial_state();
    let (mut a, mut lambda) = (vec![0.0; v.len()], vec![0.0; model.num_equations()]);
    f.accelerations(0.0, &q, &v, None, &mut a, &mut lambda).unwrap();
    (a, lambda)
}

fn close(a: Vector3<f64>, b: Vector3<f64>, scale: f64) -> bool {
    (a - b).amax() <= 1e-9 * scale
}

/// A rod welded to the wall: the wall carries the rod's weight `m g` and its moment
/// `(r − P) × m g` about the weld, and the rod does not move.
#[test]
fn cantilever_reaction_is_the_weight_and_its_moment() {
    let m = 3.0;
    let mut b = ModelBuilder::new([0.0, 0.0, -G]);
    let rod = b.body(
        Body::new("rod", m, [0.01, 0.2, 0.2])
            .at([0.5, 0.2, 0.1])
            .oriented(from_axis_angle(&Vector3::new(0.2, 0.4, 1.0), 0.6)),
    );
    b.joint(Joint::new(
        "weld",
        JointKind::Fixed,
        BodyRef::Ground,
        rod,
        [0.0, 0.2, 0.0],
        [0.0, 0.0, 1.0],
    ));
    let model = Arc::new(b.build().unwrap());
    let (a, lambda) = solve(&model);
    assert!(a.iter().all(|x| x.abs() < 1e-12), "a welded rod accelerates: {a:?}");
    let (q, _) = model.initial_state();
    let r = model.reactions(0.0, &q, &lambda)[0];
    let weight = Vector3::new(0.0, 0.0, -m * G);
    let arm = Vector3::new(0.5, 0.2, 0.1) - Vector3::new(0.0, 0.2, 0.0);
    assert!(close(r.force, weight, m * G), "force {:?}", r.force);
    assert!(close(r.moment, arm.cross(&weight), m * G), "moment {:?}", r.moment);
}

/// The heavy top in steady precession: its centre of mass runs on a horizontal circle, so the
/// pivot pushes it with `m (a − g)`, `a = −Ω² ρ` (ρ the horizontal arm); the top pushes the ground
/// with the opposite force and a ball joint carries no moment.
#[test]
fn precessing_top_loads_its_pivot_with_the_centripetal_force() {
    let (m, a_t, c, l, theta, precession) = (1.0, 0.05, 0.08, 0.3, 30f64.to_radians(), 2.0);
    let a_p = a_t + m * l * l;
    let w3 = (m * G * l + a_p * precession * precession * theta.cos()) / (c * precession);
    let p = from_axis_angle(&Vector3::y(), theta);
    let axis = rotation(&p) * Vector3::z();
    let omega = precession * Vector3::z() + (w3 - precession * theta.cos()) * axis;
    let r = l * axis;
    let mut b = ModelBuilder::new([0.0, 0.0, -G]);
    let top = b.body(
        Body::new("top", m, [a_t, a_t, c])
            .at(r.into())
            .oriented(p)
            .moving(omega.cross(&r).into(), omega.into()),
    );
    b.joint(Joint::spherical("pivot", BodyRef::Ground, top, [0.0; 3]));
    let model = Arc::new(b.build().unwrap());
    let (_, lambda) = solve(&model);
    let (q, _) = model.initial_state();
    let reaction = model.reactions(0.0, &q, &lambda)[0];
    let centripetal = -precession * precession * Vector3::new(r.x, r.y, 0.0);
    let on_top = m * (centripetal - Vector3::new(0.0, 0.0, -G));
    assert!(
        close(reaction.force, -on_top, m * G),
        "force {:?} vs {:?}",
        reaction.force,
        -on_top
    );
    assert!(
        reaction.moment.amax() < 1e-12,
        "a ball joint carried {:?}",
        reaction.moment
    );
}

/// A swinging rod with products of inertia on a hinge: the reaction obeys the rod's Newton–Euler
/// equations (`F_rod = m a − m g`, `J ω̇ + ω × J ω = M_rod + (P − r) × F_rod`, the ground getting the
/// opposite), and the hinge carries no moment about its axis.
#[test]
fn hinge_reaction_obeys_newton_euler_and_has_no_axial_moment() {
    let m = 2.0;
    let principal = [0.02, 0.3, 0.31];
    let p = from_axis_angle(&Vector3::new(1.0, 0.3, 0.5), 0.8);
    let (hinge, axis): (Vector3<f64>, Vector3<f64>) = (Vector3::zeros(), Vector3::new(0.1, 1.0, 0.2).normalize());
    let r = Vector3::new(0.6, 0.0, -0.3);
    let spin: Vector3<f64> = 1.7 * axis;
    let mut b = ModelBuilder::new([0.0, 0.0, -G]);
    let rod = b.body(
        Body::new("rod", m, principal)
            .at(r.into())
            .oriented(p)
            .moving(spin.cross(&(r - hinge)).into(), spin.into()),
    );
    b.joint(Joint::revolute(
        "hinge",
        BodyRef::Ground,
        rod,
        hinge.into(),
        axis.into(),
    ));
    let model = Arc::new(b.build().unwrap());
    let (acc, lambda) = solve(&model);
    let (q, _) = model.initial_state();
    let reaction = model.reactions(0.0, &q, &lambda)[0];
    let a_rot = rotation(&p);
    let j_global = a_rot * Matrix3::from_diagonal(&Vector3::from(principal)) * a_rot.transpose();
    let a_com = Vector3::new(acc[0], acc[1], acc[2]);
    let alpha = a_rot * Vector3::new(acc[3], acc[4], acc[5]);
    let f_rod = m * (a_com - Vector3::new(0.0, 0.0, -G));
    let m_rod = j_global * alpha + spin.cross(&(j_global * spin)) - (hinge - r).cross(&f_rod);
    let scale = m * G;
    assert!(
        close(reaction.force, -f_rod, scale),
        "force {:?} vs {:?}",
        reaction.force,
        -f_rod
    );
    assert!(
        close(reaction.moment, -m_rod, scale),
        "moment {:?} vs {:?}",
        reaction.moment,
        -m_rod
    );
    let (_, moment_local) = reaction.in_joint_axes();
    assert!(
        moment_local.z.abs() < 1e-9 * scale,
        "moment about the hinge axis {}",
        moment_local.z
    );
    assert!(
        moment_local.xy().norm() > 1e-3,
        "the test should load the hinge off its axis"
    );
}
