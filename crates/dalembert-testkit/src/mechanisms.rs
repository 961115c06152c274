//! Builders of reference mechanisms. Angles are absolute, from the global +x axis; gravity −y.

use dalembert_constraints::{Constraint, JointAngle, Model, Prismatic, Revolute};
use dalembert_kinematics::{Body, BodyId, BodyRef, ForceElement, Gravity, Torque, Vec2};
use dalembert_system::TimeFunction;
use std::sync::Arc;

/// Standard gravity used by every reference mechanism (m/s²).
pub const G: f64 = 9.81;

/// A model with a consistent initial state.
#[derive(Debug, Clone)]
pub struct Mechanism {
    /// The model.
    pub model: Arc<Model>,
    /// Positions.
    pub q: Vec<f64>,
    /// Velocities (consistent with the constraints).
    pub qd: Vec<f64>,
}

fn b(i: usize) -> BodyRef {
    BodyRef::Body(BodyId(i))
}

fn gravity() -> Box<dyn ForceElement> {
    Box::new(Gravity::new(Vec2::new(0.0, -G)))
}

/// Centre-of-mass state of a rod of length `l` whose end `p` (velocity `v`) is its pin, at angle
/// `th`, turning at `w`: `[x, y, θ]`, `[ẋ, ẏ, θ̇]`.
fn rod_from_pin(p: Vec2, v: Vec2, l: f64, th: f64, w: f64) -> ([f64; 3], [f64; 3]) {
    let (s, c) = th.sin_cos();
    let cm = p + Vec2::new(c, s) * (l / 2.0);
    let vc = v + Vec2::new(-s, c) * (l / 2.0 * w);
    ([cm.x, cm.y, th], [vc.x, vc.y, w])
}

/// A chain of uniform rods (mass `m`, length `l` each) pinned end to end, the first to the ground
/// at the origin; link `k` at absolute angle `angles[k]` turning at `rates[k]`. Optional joint
/// torques: `torques[k]` acts at joint `k` on link `k` (reaction on link `k−1` or the ground).
pub fn chain(m: f64, l: f64, angles: &[f64], rates: &[f64], torques: &[f64]) -> Mechanism {
    chain_of(&vec![m; angles.len()], l, angles, rates, torques)
}

/// [`chain`] with one mass per link.
fn chain_of(masses: &[f64], l: f64, angles: &[f64], rates: &[f64], torques: &[f64]) -> Mechanism {
    let n = angles.len();
    let mut q = Vec::with_capacity(3 * n);
    let mut qd = Vec::with_capacity(3 * n);
    let mut bodies = Vec::new();
    let mut pin = Vec2::zeros();
    let mut vpin = Vec2::zeros();
    for k in 0..n {
        let (x, v) = rod_from_pin(pin, vpin, l, angles[k], rates[k]);
        q.extend_from_slice(&x);
        qd.extend_from_slice(&v);
        let (s, c) = angles[k].sin_cos();
        pin += Vec2::new(c, s) * l;
        vpin += Vec2::new(-s, c) * (l * rates[k]);
        bodies.push(Body::rod(format!("link{k}"), masses[k], l).expect("valid rod"));
    }
    let mut joints: Vec<Box<dyn Constraint>> = Vec::new();
    for k in 0..n {
        let first = if k == 0 { BodyRef::Ground } else { b(k - 1) };
        let p_first = if k == 0 { Vec2::zeros() } else { Vec2::new(l / 2.0, 0.0) };
        joints.push(Box::new(Revolute::new(
            format!("J{k}"),
            [first, b(k)],
            [p_first, Vec2::new(-l / 2.0, 0.0)],
        )));
    }
    let mut forces = vec![gravity()];
    for (k, &tau) in torques.iter().enumerate() {
        let reaction = if k == 0 { BodyRef::Ground } else { b(k - 1) };
        forces.push(Box::new(Torque {
            name: format!("tau{k}"),
            body: b(k),
            reaction_body: reaction,
            value: TimeFunction::Constant(tau),
        }));
    }
    Mechanism {
        model: Arc::new(Model::new(bodies, forces, joints).expect("valid chain")),
        q,
        qd,
    }
}

/// Two-link arm whose joint angles are prescribed: `θ₁(t)` absolute for the first link and
/// `θ₂(t)` relative (second link to first), as polynomials `coefficients` in `t`.
pub fn driven_two_link(m: [f64; 2], l: [f64; 2], theta1: Vec<f64>, theta2_rel: Vec<f64>) -> Mechanism {
    let th1 = TimeFunction::Polynomial(theta1.clone()).eval(0.0);
    let th2 = TimeFunction::Polynomial(theta2_rel.clone()).eval(0.0);
    let (x1, v1) = rod_from_pin(Vec2::zeros(), Vec2::zeros(), l[0], th1[0], th1[1]);
    let (s, c) = th1[0].sin_cos();
    let tip = Vec2::new(c, s) * l[0];
    let vtip = Vec2::new(-s, c) * (l[0] * th1[1]);
    let (x2, v2) = rod_from_pin(tip, vtip, l[1], th1[0] + th2[0], th1[1] + th2[1]);
    let bodies = vec![
        Body::rod("link0", m[0], l[0]).expect("rod"),
        Body::rod("link1", m[1], l[1]).expect("rod"),
    ];
    let j0 = Revolute::new(
        "J0",
        [BodyRef::Ground, b(0)],
        [Vec2::zeros(), Vec2::new(-l[0] / 2.0, 0.0)],
    );
    let j1 = Revolute::new(
        "J1",
        [b(0), b(1)],
        [Vec2::new(l[0] / 2.0, 0.0), Vec2::new(-l[1] / 2.0, 0.0)],
    );
    let d0 = JointAngle::on("motor0", &j0, TimeFunction::Polynomial(theta1));
    let d1 = JointAngle::on("motor1", &j1, TimeFunction::Polynomial(theta2_rel));
    let cons: Vec<Box<dyn Constraint>> = vec![Box::new(j0), Box::new(j1), Box::new(d0), Box::new(d1)];
    let model = Arc::new(Model::new(bodies, vec![gravity()], cons).expect("valid arm"));
    Mechanism {
        model,
        q: [x1, x2].concat(),
        qd: [v1, v2].concat(),
    }
}

/// Rod-and-disk: a uniform rod (mass `mr`, length `l`) pinned to the ground at one end, and a
/// uniform disk (mass `md`, radius `r`) pinned at its centre to the rod's other end.
pub fn rod_and_disk(mr: f64, l: f64, md: f64, r: f64, theta: f64, omega: f64, disk_omega: f64) -> Mechanism {
    let (x1, v1) = rod_from_pin(Vec2::zeros(), Vec2::zeros(), l, theta, omega);
    let (s, c) = theta.sin_cos();
    let tip = Vec2::new(c, s) * l;
    let vtip = Vec2::new(-s, c) * (l * omega);
    let q = vec![x1[0], x1[1], x1[2], tip.x, tip.y, 0.3];
    let qd = vec![v1[0], v1[1], v1[2], vtip.x, vtip.y, disk_omega];
    let bodies = vec![
        Body::rod("rod", mr, l).expect("rod"),
        Body::new("disk", md, 0.5 * md * r * r).expect("disk"),
    ];
    let cons: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::new(
            "O",
            [BodyRef::Ground, b(0)],
            [Vec2::zeros(), Vec2::new(-l / 2.0, 0.0)],
        )),
        Box::new(Revolute::new(
            "A",
            [b(0), b(1)],
            [Vec2::new(l / 2.0, 0.0), Vec2::zeros()],
        )),
    ];
    Mechanism {
        model: Arc::new(Model::new(bodies, vec![gravity()], cons).expect("valid")),
        q,
        qd,
    }
}

/// A point mass `m` (zero inertia) on a massless string of length `l` from the origin, at angle
/// `phi` from the downward vertical, swinging at `phi_dot`. The body's reference point is the bob;
/// the pin is at local `(−l, 0)` and the body angle is `phi − π/2`.
pub fn point_pendulum(m: f64, l: f64, phi: f64, phi_dot: f64) -> Mechanism {
    let th = phi - std::f64::consts::FRAC_PI_2;
    let (s, c) = th.sin_cos();
    let q = vec![l * c, l * s, th];
    let qd = vec![-l * s * phi_dot, l * c * phi_dot, phi_dot];
    let bodies = vec![Body::new("bob", m, 0.0).expect("bob")];
    let cons: Vec<Box<dyn Constraint>> = vec![Box::new(Revolute::new(
        "pivot",
        [BodyRef::Ground, b(0)],
        [Vec2::zeros(), Vec2::new(-l, 0.0)],
    ))];
    Mechanism {
        model: Arc::new(Model::new(bodies, vec![gravity()], cons).expect("valid")),
        q,
        qd,
    }
}

/// The four-bar of `shared/anchors`: ground pivots A = (0,0), D = (2,0); crank AB = 1 m, coupler
/// BC = 2.5 m, rocker DC = 1.5 m; uniform rods of 1 kg/m. Crank at angle `phi` turning at
/// `phi_dot`, elbow-down assembly. With `crank_torque` a constant torque drives the crank; with
/// `driven` the crank angle is prescribed as `phi + phi_dot t` instead.
pub fn four_bar(phi: f64, phi_dot: f64, crank_torque: f64, driven: bool) -> Mechanism {
    let k = crate::closed_form::FourBar::ANCHOR;
    let (q, qd) = k.state(phi, phi_dot);
    let bodies = vec![
        Body::rod("crank", k.a, k.a).expect("rod"),
        Body::rod("coupler", k.b, k.b).expect("rod"),
        Body::rod("rocker", k.c, k.c).expect("rod"),
    ];
    let ja = Revolute::new(
        "A",
        [BodyRef::Ground, b(0)],
        [Vec2::zeros(), Vec2::new(-k.a / 2.0, 0.0)],
    );
    let mut cons: Vec<Box<dyn Constraint>> = vec![
        Box::new(ja.clone()),
        Box::new(Revolute::new(
            "B",
            [b(0), b(1)],
            [Vec2::new(k.a / 2.0, 0.0), Vec2::new(-k.b / 2.0, 0.0)],
        )),
        Box::new(Revolute::new(
            "C",
            [b(1), b(2)],
            [Vec2::new(k.b / 2.0, 0.0), Vec2::new(k.c / 2.0, 0.0)],
        )),
        Box::new(Revolute::new(
            "D",
            [BodyRef::Ground, b(2)],
            [Vec2::new(k.d, 0.0), Vec2::new(-k.c / 2.0, 0.0)],
        )),
    ];
    if driven {
        cons.push(Box::new(JointAngle::on(
            "crank-motor",
            &ja,
            TimeFunction::Linear {
                initial: phi,
                rate: phi_dot,
            },
        )));
    }
    let mut forces = vec![gravity()];
    if crank_torque != 0.0 {
        forces.push(Box::new(Torque::on(
            "crank-torque",
            b(0),
            TimeFunction::Constant(crank_torque),
        )));
    }
    Mechanism {
        model: Arc::new(Model::new(bodies, forces, cons).expect("valid four-bar")),
        q,
        qd,
    }
}

/// The slider-crank of `shared/anchors`: crank 0.5 m (0.5 kg) about the origin, rod 2 m (2 kg),
/// slider 1 kg (point mass) on the x axis; crank at `phi` turning at `phi_dot`.
pub fn slider_crank(phi: f64, phi_dot: f64) -> Mechanism {
    let (r, l) = (0.5, 2.0);
    let (s, c) = phi.sin_cos();
    let pb = Vec2::new(r * c, r * s);
    let root = (l * l - r * r * s * s).sqrt();
    let xc = r * c + root;
    let beta = (-r * s / l).asin();
    let xd = -r * s * phi_dot - r * r * s * c * phi_dot / root;
    let betad = -r * c * phi_dot / (l * beta.cos());
    let vb = Vec2::new(-r * s * phi_dot, r * c * phi_dot);
    let q = vec![
        pb.x / 2.0,
        pb.y / 2.0,
        phi,
        (pb.x + xc) / 2.0,
        pb.y / 2.0,
        beta,
        xc,
        0.0,
        0.0,
    ];
    let qd = vec![
        vb.x / 2.0,
        vb.y / 2.0,
        phi_dot,
        (vb.x + xd) / 2.0,
        vb.y / 2.0,
        betad,
        xd,
        0.0,
        0.0,
    ];
    let bodies = vec![
        Body::rod("crank", 0.5, r).expect("rod"),
        Body::rod("rod", 2.0, l).expect("rod"),
        Body::new("slider", 1.0, 0.0).expect("slider"),
    ];
    let cons: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::new(
            "O",
            [BodyRef::Ground, b(0)],
            [Vec2::zeros(), Vec2::new(-r / 2.0, 0.0)],
        )),
        Box::new(Revolute::new(
            "B",
            [b(0), b(1)],
            [Vec2::new(r / 2.0, 0.0), Vec2::new(-l / 2.0, 0.0)],
        )),
        Box::new(Revolute::new(
            "C",
            [b(1), b(2)],
            [Vec2::new(l / 2.0, 0.0), Vec2::zeros()],
        )),
        Box::new(Prismatic {
            name: "guide".into(),
            bodies: [BodyRef::Ground, b(2)],
            points: [Vec2::zeros(), Vec2::zeros()],
            axis: Vec2::x(),
            angle: 0.0,
        }),
    ];
    Mechanism {
        model: Arc::new(Model::new(bodies, vec![gravity()], cons).expect("valid slider-crank")),
        q,
        qd,
    }
}

/// A double pendulum of two uniform rods with `dp`'s masses and lengths, absolute angles `th`,
/// rates `w`, and joint torques `tau` (τ₁ ground→link 1, τ₂ link 1→link 2).
pub fn double_pendulum(dp: crate::closed_form::DoublePendulum, th: [f64; 2], w: [f64; 2], tau: [f64; 2]) -> Mechanism {
    let [l1, l2] = dp.l;
    let (s1, c1) = th[0].sin_cos();
    let (s2, c2) = th[1].sin_cos();
    let q = vec![
        l1 / 2.0 * c1,
        l1 / 2.0 * s1,
        th[0],
        l1 * c1 + l2 / 2.0 * c2,
        l1 * s1 + l2 / 2.0 * s2,
        th[1],
    ];
    let qd = vec![
        -l1 / 2.0 * s1 * w[0],
        l1 / 2.0 * c1 * w[0],
        w[0],
        -l1 * s1 * w[0] - l2 / 2.0 * s2 * w[1],
        l1 * c1 * w[0] + l2 / 2.0 * c2 * w[1],
        w[1],
    ];
    let bodies = vec![
        Body::rod("l1", dp.m[0], l1).unwrap(),
        Body::rod("l2", dp.m[1], l2).unwrap(),
    ];
    let cons: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::new(
            "J0",
            [BodyRef::Ground, b(0)],
            [Vec2::zeros(), Vec2::new(-l1 / 2.0, 0.0)],
        )),
        Box::new(Revolute::new(
            "J1",
            [b(0), b(1)],
            [Vec2::new(l1 / 2.0, 0.0), Vec2::new(-l2 / 2.0, 0.0)],
        )),
    ];
    let forces: Vec<Box<dyn ForceElement>> = vec![
        Box::new(Gravity::new(Vec2::new(0.0, -G))),
        Box::new(Torque {
            name: "tau0".into(),
            body: b(0),
            reaction_body: BodyRef::Ground,
            value: TimeFunction::Constant(tau[0]),
        }),
        Box::new(Torque {
            name: "tau1".into(),
            body: b(1),
            reaction_body: b(0),
            value: TimeFunction::Constant(tau[1]),
        }),
    ];
    Mechanism {
        model: Arc::new(Model::new(bodies, forces, cons).unwrap()),
        q,
        qd,
    }
}

/// A chain of uniform rods of length `l` with the given masses (one per link), pinned end to end
/// from the origin, at absolute angles `angles`, at rest.
pub fn chain_with_masses(masses: &[f64], l: f64, angles: &[f64]) -> Mechanism {
    chain_of(masses, l, angles, &vec![0.0; angles.len()], &[])
}

/// A parallelogram: two cranks (1 kg, 1 m) pinned to the ground at (0, 0) and (2, 0), joined by a
/// coupler (2 kg, 2 m); with `extra_crank` a third, redundant crank from (1, 0) to the coupler's
/// middle. Cranks at angle `phi` turning at `phi_dot`. Every crank shares one angle: the motion is
/// `(2/3 + 2 [+ 1/3]) φ̈ = −g (1 + 2 [+ 0.5]) cos φ`.
pub fn parallelogram(phi: f64, phi_dot: f64, extra_crank: bool) -> Mechanism {
    let u = Vec2::new(phi.cos(), phi.sin());
    let v = Vec2::new(-phi.sin(), phi.cos()) * phi_dot;
    let mut q = vec![
        u.x / 2.0,
        u.y / 2.0,
        phi,
        1.0 + u.x,
        u.y,
        0.0,
        2.0 + u.x / 2.0,
        u.y / 2.0,
        phi,
    ];
    let mut qd = vec![
        v.x / 2.0,
        v.y / 2.0,
        phi_dot,
        v.x,
        v.y,
        0.0,
        v.x / 2.0,
        v.y / 2.0,
        phi_dot,
    ];
    let mut bodies = vec![
        Body::rod("crank1", 1.0, 1.0).expect("rod"),
        Body::rod("coupler", 2.0, 2.0).expect("rod"),
        Body::rod("crank2", 1.0, 1.0).expect("rod"),
    ];
    if extra_crank {
        q.extend_from_slice(&[1.0 + u.x / 2.0, u.y / 2.0, phi]);
        qd.extend_from_slice(&[v.x / 2.0, v.y / 2.0, phi_dot]);
        bodies.push(Body::rod("crank3", 1.0, 1.0).expect("rod"));
    }
    let g = BodyRef::Ground;
    let mut joints: Vec<Box<dyn Constraint>> = vec![
        Box::new(Revolute::at("A", [g, b(0)], Vec2::zeros(), &q)),
        Box::new(Revolute::at("B", [b(0), b(1)], u, &q)),
        Box::new(Revolute::at("C", [b(1), b(2)], Vec2::new(2.0, 0.0) + u, &q)),
        Box::new(Revolute::at("D", [g, b(2)], Vec2::new(2.0, 0.0), &q)),
    ];
    if extra_crank {
        joints.push(Box::new(Revolute::at("E", [g, b(3)], Vec2::new(1.0, 0.0), &q)));
        joints.push(Box::new(Revolute::at("F", [b(3), b(1)], Vec2::new(1.0, 0.0) + u, &q)));
    }
    Mechanism {
        model: Arc::new(Model::new(bodies, vec![gravity()], joints).expect("valid parallelogram")),
        q,
        qd,
    }
}

/// A slider of 1 kg (inertia 0.1) on a frictionless guide along x, held by a spring of stiffness
/// `k` (N/m, free length 1 m) to the origin, released from rest 1 mm stretched: natural frequency
/// `√k` rad/s, initial energy `½ k 1e-6` J.
pub fn slider_on_spring(k: f64) -> Mechanism {
    use dalembert_kinematics::SpringDamper;
    let q = vec![1.001, 0.0, 0.0];
    let guide: Box<dyn Constraint> = Box::new(Prismatic::at(
        "guide",
        [BodyRef::Ground, b(0)],
        Vec2::new(1.0, 0.0),
        Vec2::x(),
        &q,
    ));
    let spring = SpringDamper {
        name: "spring".into(),
        bodies: (BodyRef::Ground, b(0)),
        points: (Vec2::zeros(), Vec2::zeros()),
        stiffness: k,
        damping: 0.0,
        free_length: 1.0,
        actuator: None,
    };
    let model = Model::new(
        vec![Body::new("mass", 1.0, 0.1).expect("body")],
        vec![Box::new(spring)],
        vec![guide],
    )
    .expect("valid");
    Mechanism {
        model: Arc::new(model),
        q,
        qd: vec![0.0; 3],
    }
}
